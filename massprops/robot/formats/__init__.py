"""Parsers: URDF, SDF (with model:// includes), MJCF (with includes, frames, replicate,
attach), xacro, into the neutral `massprops.robot.model`; line numbers and byte spans kept."""
