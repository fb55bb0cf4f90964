file(REMOVE_RECURSE
  "CMakeFiles/minimal_asan.dir/__/cpp_examples/minimal.c.o"
  "CMakeFiles/minimal_asan.dir/__/cpp_examples/minimal.c.o.d"
  "minimal_asan"
  "minimal_asan.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang C)
  include(CMakeFiles/minimal_asan.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
