# Empty custom commands generated dependencies file for pelage_cargo.
# This may be replaced when dependencies are built.
