# Empty dependencies file for c_contract_asan.
# This may be replaced when dependencies are built.
