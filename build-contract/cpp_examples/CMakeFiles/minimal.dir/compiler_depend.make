# Empty compiler generated dependencies file for minimal.
# This may be replaced when dependencies are built.
