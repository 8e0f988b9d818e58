# The common build of the ROS-free core libraries under src/ (plain CMake, usable without ROS):
# the library from src/*.cpp, one executable per tools/*.cpp and bench/*.cpp, one gtest binary
# from test/*_test.cpp, and an installed, exported <name>::<name> target for find_package(<name>).
# Usage, in src/<name>/CMakeLists.txt after project(<name> ...):
#   include(${CMAKE_CURRENT_SOURCE_DIR}/../cmake/core_library.cmake)
#   core_library_begin(<PREFIX>)           # language settings, options <PREFIX>_WERROR,
#                                          # <PREFIX>_BUILD_TOOLS, <PREFIX>_BUILD_BENCHMARKS
#   ... find_package(...) ...
#   core_library_add(<name> <PREFIX> <public link libraries>...)
#   ... library-specific settings ...
# A core split by dependency instead builds one static library per component and an interface
# target <name>::<name> that links them all (in place of core_library_add):
#   core_library_component(<name> <PREFIX> <component> <public link libraries>...)   # per component
#   core_library_umbrella(<name> <PREFIX>)
# Component <c>: sources src/<c>/*.cpp, headers include/<name>/<c>/, target <name>_<c>, exported
# as <name>::<c>.
#   core_library_end(<name> <PREFIX>)      # tools, benchmarks, tests, install and export
# Extra libraries for the tools, benchmarks and tests: <PREFIX>_TOOL_LIBS, <PREFIX>_BENCH_LIBS,
# <PREFIX>_TEST_LIBS (set them before core_library_end, e.g. in cmake/<name>_extras.cmake).

macro(core_library_begin prefix)
  set(CMAKE_CXX_STANDARD 17)
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
  set(CMAKE_CXX_EXTENSIONS OFF)
  set(CMAKE_POSITION_INDEPENDENT_CODE ON)  # linked into nodelet shared objects
  set(CMAKE_EXPORT_COMPILE_COMMANDS ON)
  if(NOT CMAKE_BUILD_TYPE)
    set(CMAKE_BUILD_TYPE RelWithDebInfo)
  endif()
  option(${prefix}_WERROR "Treat warnings as errors in project code" ON)
  option(${prefix}_BUILD_TOOLS "Build command-line tools" ON)
  option(${prefix}_BUILD_BENCHMARKS "Build benchmarks (needs Google Benchmark)" ON)
  include(CTest)  # defines BUILD_TESTING (default ON)
  set(${prefix}_WARNINGS -Wall -Wextra -Wpedantic)
  if(${prefix}_WERROR)
    list(APPEND ${prefix}_WARNINGS -Werror)
  endif()
endmacro()

# Every .cpp under src/ is part of the library; add files without editing a list.
macro(core_library_add name prefix)
  file(GLOB ${prefix}_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  add_library(${name} STATIC ${${prefix}_SOURCES})
  add_library(${name}::${name} ALIAS ${name})
  target_include_directories(${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(${name} PUBLIC ${ARGN})
  target_compile_options(${name} PRIVATE ${${prefix}_WARNINGS})
  target_compile_features(${name} PUBLIC cxx_std_17)
endmacro()

# One component of a core split by dependency (see the top of this file).
macro(core_library_component name prefix component)
  file(GLOB ${prefix}_${component}_SOURCES CONFIGURE_DEPENDS
       ${CMAKE_CURRENT_SOURCE_DIR}/src/${component}/*.cpp)
  add_library(${name}_${component} STATIC ${${prefix}_${component}_SOURCES})
  add_library(${name}::${component} ALIAS ${name}_${component})
  set_target_properties(${name}_${component} PROPERTIES EXPORT_NAME ${component})
  target_include_directories(${name}_${component} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:include>)
  target_link_libraries(${name}_${component} PUBLIC ${ARGN})
  target_compile_options(${name}_${component} PRIVATE ${${prefix}_WARNINGS})
  target_compile_features(${name}_${component} PUBLIC cxx_std_17)
  list(APPEND ${prefix}_COMPONENTS ${name}_${component})
endmacro()

# <name>::<name> of a split core: an interface target linking every component.
macro(core_library_umbrella name prefix)
  add_library(${name} INTERFACE)
  add_library(${name}::${name} ALIAS ${name})
  target_link_libraries(${name} INTERFACE ${${prefix}_COMPONENTS})
endmacro()

macro(core_library_end name prefix)
  include(cmake/${name}_extras.cmake OPTIONAL)

  # Tools: one executable per tools/<tool>.cpp, installed as <name>_<tool>.
  if(${prefix}_BUILD_TOOLS)
    file(GLOB ${prefix}_TOOLS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/tools/*.cpp)
    foreach(tool_src ${${prefix}_TOOLS})
      get_filename_component(tool ${tool_src} NAME_WE)
      add_executable(${name}_${tool} ${tool_src})
      target_link_libraries(${name}_${tool} PRIVATE ${name}::${name} ${${prefix}_TOOL_LIBS})
      target_compile_options(${name}_${tool} PRIVATE ${${prefix}_WARNINGS})
      install(TARGETS ${name}_${tool} RUNTIME DESTINATION bin)
    endforeach()
  endif()

  # Benchmarks: one executable per bench/<bench>.cpp (Google Benchmark), not run by the tests.
  if(${prefix}_BUILD_BENCHMARKS)
    find_package(benchmark QUIET)
    if(benchmark_FOUND)
      file(GLOB ${prefix}_BENCHES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/bench/*.cpp)
      foreach(bench_src ${${prefix}_BENCHES})
        get_filename_component(bench ${bench_src} NAME_WE)
        add_executable(${name}_${bench} ${bench_src})
        target_link_libraries(${name}_${bench} PRIVATE ${name}::${name} benchmark::benchmark
                              ${${prefix}_BENCH_LIBS})
        target_compile_options(${name}_${bench} PRIVATE ${${prefix}_WARNINGS})
        install(TARGETS ${name}_${bench} RUNTIME DESTINATION bin)
      endforeach()
    endif()
  endif()

  # Tests: every test/*_test.cpp goes into one gtest binary; each TEST is one ctest test. Tests
  # that read ../shared/data find it through <PREFIX>_SHARED_DATA_DIR; where the repository ships
  # an excerpt of the same data (test/data/sample_session, <PREFIX>_SAMPLE_SESSION_DIR), they test
  # the excerpt always and the full data when present, else they skip when it is absent.
  if(BUILD_TESTING)
    find_package(GTest REQUIRED)
    include(GoogleTest)
    file(GLOB ${prefix}_TEST_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/*_test.cpp)
    if(${prefix}_TEST_SOURCES)
      add_executable(${name}_tests ${${prefix}_TEST_SOURCES})
      target_link_libraries(${name}_tests PRIVATE ${name}::${name} GTest::gtest GTest::gtest_main
                            ${${prefix}_TEST_LIBS})
      # The test programs themselves at -O1 (the libraries they test keep their -O2/-O3): about a
      # quarter less compile time, the same results (no fast-math at any level).
      target_compile_options(${name}_tests PRIVATE ${${prefix}_WARNINGS}
                             $<$<NOT:$<CONFIG:Debug>>:-O1>)
      # Tests may check the library's internal headers under src/ (e.g. dasp's simd.h).
      target_include_directories(${name}_tests PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
      get_filename_component(${prefix}_REPO_ROOT ${CMAKE_CURRENT_SOURCE_DIR}/../.. ABSOLUTE)
      target_compile_definitions(${name}_tests PRIVATE
        ${prefix}_SHARED_DATA_DIR="${${prefix}_REPO_ROOT}/../shared/data"
        ${prefix}_TEST_DATA_DIR="${CMAKE_CURRENT_SOURCE_DIR}/test/data"
        ${prefix}_SAMPLE_SESSION_DIR="${${prefix}_REPO_ROOT}/test/data/sample_session")
      gtest_discover_tests(${name}_tests DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60)
    endif()
  endif()

  # Install and export <name>::<name> (and a split core's <name>::<component>) so that
  # find_package(<name>) works from another project.
  include(GNUInstallDirs)
  include(CMakePackageConfigHelpers)
  install(TARGETS ${name} ${${prefix}_COMPONENTS} EXPORT ${name}Targets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(EXPORT ${name}Targets NAMESPACE ${name}:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/${name})
  configure_package_config_file(cmake/${name}Config.cmake.in
    ${CMAKE_CURRENT_BINARY_DIR}/${name}Config.cmake
    INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/${name})
  write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/${name}ConfigVersion.cmake
    COMPATIBILITY SameMajorVersion)
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/${name}Config.cmake
                ${CMAKE_CURRENT_BINARY_DIR}/${name}ConfigVersion.cmake
    DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/${name})
  install(FILES package.xml DESTINATION share/${name})
endmacro()
