# Empty dependencies file for embree_interp.
# This may be replaced when dependencies are built.
