file(REMOVE_RECURSE
  "CMakeFiles/c_contract.dir/c/c_contract.c.o"
  "CMakeFiles/c_contract.dir/c/c_contract.c.o.d"
  "c_contract"
  "c_contract.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang C)
  include(CMakeFiles/c_contract.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
