file(REMOVE_RECURSE
  "CMakeFiles/embree_stamp.dir/cpp/embree_stamp.cpp.o"
  "CMakeFiles/embree_stamp.dir/cpp/embree_stamp.cpp.o.d"
  "embree_stamp"
  "embree_stamp.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/embree_stamp.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
