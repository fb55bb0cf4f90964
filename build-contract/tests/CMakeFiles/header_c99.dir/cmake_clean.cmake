file(REMOVE_RECURSE
  "CMakeFiles/header_c99.dir/c/header_c99.c.o"
  "CMakeFiles/header_c99.dir/c/header_c99.c.o.d"
  "header_c99"
  "header_c99.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang C)
  include(CMakeFiles/header_c99.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
