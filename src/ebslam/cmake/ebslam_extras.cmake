# Extra dependencies of the ebslam tools, benchmarks and tests (included by CMakeLists.txt).

# Command-line tools parse their arguments with CLI11 (header-only); the library never uses it.
if(EBSLAM_BUILD_TOOLS)
  find_package(CLI11 REQUIRED)
  list(APPEND EBSLAM_TOOL_LIBS CLI11::CLI11)
endif()
