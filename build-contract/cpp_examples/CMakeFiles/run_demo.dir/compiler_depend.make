# Empty custom commands generated dependencies file for run_demo.
# This may be replaced when dependencies are built.
