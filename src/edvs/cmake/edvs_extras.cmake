# Extra dependencies of the edvs tools and the fuzz targets (included by CMakeLists.txt).

# Command-line tools parse their arguments with CLI11 (header-only); the library never uses it.
if(EDVS_BUILD_TOOLS)
  find_package(CLI11 REQUIRED)
  list(APPEND EDVS_TOOL_LIBS CLI11::CLI11)
endif()

# libFuzzer targets, only with clang: configure with -DCMAKE_CXX_COMPILER=clang++
# -DEDVS_BUILD_FUZZERS=ON (fuzz/run_fuzz.sh compiles them directly in its own build folder).
option(EDVS_BUILD_FUZZERS "Build the libFuzzer targets (needs clang)" OFF)
if(EDVS_BUILD_FUZZERS AND CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  foreach(fuzzer parser_fuzzer uri_fuzzer)
    add_executable(edvs_${fuzzer} ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/${fuzzer}.cpp)
    target_link_libraries(edvs_${fuzzer} edvs::edvs)
    target_compile_options(edvs_${fuzzer} PRIVATE -fsanitize=fuzzer,address,undefined)
    target_link_options(edvs_${fuzzer} PRIVATE -fsanitize=fuzzer,address,undefined)
  endforeach()
endif()
