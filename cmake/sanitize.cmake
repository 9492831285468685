# The checked build (FACET_SANITIZE=ON): the product (core, and the app the offscreen suites
# drive) built with AddressSanitizer (with its leak checker) and UndefinedBehaviorSanitizer;
# the suites and benchmarks link the runtimes but their own code is not instrumented
# (tests/CMakeLists.txt says why). UB aborts rather
# than printing and going on, so a report fails the test that caused it. scripts/test.sh
# builds it with FACET_SANITIZE=1 (in build/checked, with clang).
#
# -O1 keeps the sanitized suites fast enough for CI and the stack traces readable; line
# tables alone symbolize a report at a fraction of the compile and link cost of full debug
# info. The build type still decides NDEBUG. clang is preferred so that the same tree also
# builds the libFuzzer targets (-DFACET_BUILD_FUZZ=ON, tests/fuzz): one checked build serves
# the suites and the fuzzers.
set(facet_sanitizers address,undefined)
# Four of UBSan's checks are left out: alignment, null, object-size and pointer-overflow sit
# on every element access of Eigen's code and doubled the core's compile time (two_view.cpp:
# 126 s, 66 s without them, 61 s with ASan alone), while ASan already stops a bad access
# through a wild or null pointer. The checks that found this tree's bugs stay (float-cast-
# overflow, signed overflow, shifts, bounds, enum and bool values, division by zero).
set(facet_sanitize_flags -fsanitize=${facet_sanitizers}
                         -fno-sanitize=alignment,null,object-size,pointer-overflow
                         -fno-sanitize-recover=undefined -fno-omit-frame-pointer -O1)
if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  list(APPEND facet_sanitize_flags -gline-tables-only)
else()
  list(APPEND facet_sanitize_flags -g1)
endif()
# Compile options come after CMAKE_CXX_FLAGS_<CONFIG> on the command line, so this -O1 wins
# over the build type's -O2/-O3.
add_compile_options(${facet_sanitize_flags})
add_link_options(-fsanitize=${facet_sanitizers})
# LLVM's linker (lld-14, scripts/deps-debian.txt's checked part) when clang has it: this tree
# links about a hundred sanitized executables, each 5x faster with lld than with GNU ld.
if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  find_program(FACET_LLD NAMES ld.lld-14 ld.lld)
  if(FACET_LLD)
    add_link_options(--ld-path=${FACET_LLD})
  endif()
endif()
message(STATUS "Facet: checked build (${facet_sanitizers}) with ${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}")
