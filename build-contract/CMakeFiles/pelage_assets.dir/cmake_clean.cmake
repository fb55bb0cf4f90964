file(REMOVE_RECURSE
  "CMakeFiles/pelage_assets"
  "assets/creature.obj"
  "assets/creature_density.png"
)

# Per-language clean rules from dependency scanning.
foreach(lang )
  include(CMakeFiles/pelage_assets.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
