file(REMOVE_RECURSE
  "CMakeFiles/ubsan_canary.dir/c/ubsan_canary.c.o"
  "CMakeFiles/ubsan_canary.dir/c/ubsan_canary.c.o.d"
  "ubsan_canary"
  "ubsan_canary.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang C)
  include(CMakeFiles/ubsan_canary.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
