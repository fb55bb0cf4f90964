file(REMOVE_RECURSE
  "CMakeFiles/minimal.dir/minimal.c.o"
  "CMakeFiles/minimal.dir/minimal.c.o.d"
  "minimal"
  "minimal.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang C)
  include(CMakeFiles/minimal.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
