# Empty dependencies file for header_cxx17.
# This may be replaced when dependencies are built.
