file(REMOVE_RECURSE
  "CMakeFiles/creature_io.dir/creature_io.cpp.o"
  "CMakeFiles/creature_io.dir/creature_io.cpp.o.d"
  "libcreature_io.a"
  "libcreature_io.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/creature_io.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
