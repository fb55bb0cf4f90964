# Empty compiler generated dependencies file for asan_canary.
# This may be replaced when dependencies are built.
