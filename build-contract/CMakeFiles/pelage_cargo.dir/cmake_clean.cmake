file(REMOVE_RECURSE
  "/work/main/target/release/libpelage.a"
  "CMakeFiles/pelage_cargo"
)

# Per-language clean rules from dependency scanning.
foreach(lang )
  include(CMakeFiles/pelage_cargo.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
