"""Each format's ``<inertial>`` element, and write-back into the description's bytes."""
