# Empty dependencies file for ubsan_canary.
# This may be replaced when dependencies are built.
