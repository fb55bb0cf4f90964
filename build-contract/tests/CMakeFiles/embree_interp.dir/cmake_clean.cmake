file(REMOVE_RECURSE
  "CMakeFiles/embree_interp.dir/cpp/embree_interp.cpp.o"
  "CMakeFiles/embree_interp.dir/cpp/embree_interp.cpp.o.d"
  "embree_interp"
  "embree_interp.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/embree_interp.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
