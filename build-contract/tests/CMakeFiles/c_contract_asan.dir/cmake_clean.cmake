file(REMOVE_RECURSE
  "CMakeFiles/c_contract_asan.dir/c/c_contract.c.o"
  "CMakeFiles/c_contract_asan.dir/c/c_contract.c.o.d"
  "c_contract_asan"
  "c_contract_asan.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang C)
  include(CMakeFiles/c_contract_asan.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
