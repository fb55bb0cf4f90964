# CMake generated Testfile for 
# Source directory: /work/main/cpp_examples
# Build directory: /work/main/build-contract/cpp_examples
# 
# This file includes the relevant testing commands required for 
# testing this directory and lists subdirectories to be tested as well.
