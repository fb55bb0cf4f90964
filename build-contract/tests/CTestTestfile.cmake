# CMake generated Testfile for 
# Source directory: /work/main/tests
# Build directory: /work/main/build-contract/tests
# 
# This file includes the relevant testing commands required for 
# testing this directory and lists subdirectories to be tested as well.
add_test([=[header_c99]=] "/work/main/build-contract/tests/header_c99")
set_tests_properties([=[header_c99]=] PROPERTIES  _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;20;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[header_cxx17]=] "/work/main/build-contract/tests/header_cxx17")
set_tests_properties([=[header_cxx17]=] PROPERTIES  _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;26;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[c_contract]=] "/work/main/build-contract/tests/c_contract")
set_tests_properties([=[c_contract]=] PROPERTIES  _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;32;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[c_contract_asan]=] "/work/main/build-contract/tests/c_contract_asan")
set_tests_properties([=[c_contract_asan]=] PROPERTIES  ENVIRONMENT "ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1;UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;48;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[minimal_asan]=] "/work/main/build-contract/tests/minimal_asan")
set_tests_properties([=[minimal_asan]=] PROPERTIES  ENVIRONMENT "ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1;UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;50;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[asan_instrumented]=] "/usr/bin/nm" "/work/main/build-contract/tests/c_contract_asan")
set_tests_properties([=[asan_instrumented]=] PROPERTIES  PASS_REGULAR_EXPRESSION "__asan_init" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;55;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[ubsan_instrumented]=] "/usr/bin/nm" "/work/main/build-contract/tests/c_contract_asan")
set_tests_properties([=[ubsan_instrumented]=] PROPERTIES  PASS_REGULAR_EXPRESSION "__ubsan_handle_" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;57;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[asan_canary]=] "/work/main/build-contract/tests/asan_canary")
set_tests_properties([=[asan_canary]=] PROPERTIES  ENVIRONMENT "ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1;UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1" PASS_REGULAR_EXPRESSION "ERROR: AddressSanitizer: heap-use-after-free" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;60;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[ubsan_canary]=] "/work/main/build-contract/tests/ubsan_canary")
set_tests_properties([=[ubsan_canary]=] PROPERTIES  ENVIRONMENT "ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1;UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1" PASS_REGULAR_EXPRESSION "runtime error: signed integer overflow" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;64;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[valgrind_minimal]=] "/usr/bin/valgrind" "--error-exitcode=1" "--leak-check=full" "--errors-for-leak-kinds=definite,indirect,possible" "--suppressions=/work/main/build-contract/tests/rust_std.supp" "/work/main/build-contract/cpp_examples/minimal")
set_tests_properties([=[valgrind_minimal]=] PROPERTIES  _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;88;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[valgrind_c_contract]=] "/usr/bin/valgrind" "--error-exitcode=1" "--leak-check=full" "--errors-for-leak-kinds=definite,indirect,possible" "--suppressions=/work/main/build-contract/tests/rust_std.supp" "/work/main/build-contract/tests/c_contract")
set_tests_properties([=[valgrind_c_contract]=] PROPERTIES  _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;88;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[embree_stamp]=] "/work/main/build-contract/tests/embree_stamp" "/work/main/build-contract/assets/creature.obj" "/work/main/build-contract/assets/creature_density.png")
set_tests_properties([=[embree_stamp]=] PROPERTIES  TIMEOUT "600" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;107;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[embree_interp]=] "/work/main/build-contract/tests/embree_interp" "/work/main/build-contract/assets/creature.obj" "/work/main/build-contract/assets/creature_density.png")
set_tests_properties([=[embree_interp]=] PROPERTIES  RUN_SERIAL "TRUE" TIMEOUT "600" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;114;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[find_package_consumer]=] "/usr/bin/cmake" "-DBUILD_DIR=/work/main/build-contract" "-DCONSUMER_DIR=/work/main/tests/cpp/find_package_consumer" "-DWORK_DIR=/work/main/build-contract/tests/find_package_consumer" "-DCONFIG=Release" "-DGENERATOR=Unix Makefiles" "-DCXX_COMPILER=/usr/bin/c++" "-DPKG_CONFIG=/usr/bin/pkg-config" "-DEXPECTED_VERSION=0.6.0" "-P" "/work/main/tests/cpp/find_package_consumer/run_install_test.cmake")
set_tests_properties([=[find_package_consumer]=] PROPERTIES  TIMEOUT "300" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;120;add_test;/work/main/tests/CMakeLists.txt;0;")
