# Empty dependencies file for embree_stamp.
# This may be replaced when dependencies are built.
