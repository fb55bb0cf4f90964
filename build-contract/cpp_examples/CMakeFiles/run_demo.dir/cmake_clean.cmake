file(REMOVE_RECURSE
  "CMakeFiles/run_demo"
)

# Per-language clean rules from dependency scanning.
foreach(lang )
  include(CMakeFiles/run_demo.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
