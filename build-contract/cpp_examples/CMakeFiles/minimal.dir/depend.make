# Empty dependencies file for minimal.
# This may be replaced when dependencies are built.
