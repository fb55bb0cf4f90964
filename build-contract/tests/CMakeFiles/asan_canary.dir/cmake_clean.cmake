file(REMOVE_RECURSE
  "CMakeFiles/asan_canary.dir/c/asan_canary.c.o"
  "CMakeFiles/asan_canary.dir/c/asan_canary.c.o.d"
  "asan_canary"
  "asan_canary.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang C)
  include(CMakeFiles/asan_canary.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
