# Empty dependencies file for minimal_asan.
# This may be replaced when dependencies are built.
