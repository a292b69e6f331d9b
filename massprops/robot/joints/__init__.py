"""The description as a mechanism: `RobotJoint` values and link poses at the zero pose
(`frames`, its docstring states the frames), one reader per format."""
