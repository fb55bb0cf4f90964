# Empty dependencies file for asan_canary.
# This may be replaced when dependencies are built.
