# Empty dependencies file for c_contract.
# This may be replaced when dependencies are built.
