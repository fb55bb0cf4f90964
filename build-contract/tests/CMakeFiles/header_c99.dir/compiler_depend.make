# Empty compiler generated dependencies file for header_c99.
# This may be replaced when dependencies are built.
