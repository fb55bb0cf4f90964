# Empty dependencies file for creature_io.
# This may be replaced when dependencies are built.
