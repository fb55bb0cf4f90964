file(REMOVE_RECURSE
  "CMakeFiles/header_cxx17.dir/cpp/header_cxx17.cpp.o"
  "CMakeFiles/header_cxx17.dir/cpp/header_cxx17.cpp.o.d"
  "header_cxx17"
  "header_cxx17.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/header_cxx17.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
