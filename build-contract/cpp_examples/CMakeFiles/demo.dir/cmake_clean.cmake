file(REMOVE_RECURSE
  "CMakeFiles/demo.dir/demo.cpp.o"
  "CMakeFiles/demo.dir/demo.cpp.o.d"
  "demo"
  "demo.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/demo.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
