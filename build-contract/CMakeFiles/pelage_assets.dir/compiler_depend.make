# Empty custom commands generated dependencies file for pelage_assets.
# This may be replaced when dependencies are built.
