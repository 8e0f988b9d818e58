# Extra dependencies of the dasp tools: OpenCV ximgproc and PCL supervoxels for the peer methods
# (library dasp_peers, tools/peers/), the parts of dasp_sdasp (tools/sdasp/), CLI11 and
# nlohmann-json for the command lines. They are linked into the tools only, never into the dasp
# library itself.
if(DASP_BUILD_TOOLS)
  find_package(CLI11 REQUIRED)
  find_package(nlohmann_json 3 REQUIRED)
  find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs ximgproc)
  # Debian's VTK (pulled in by PCLConfig) references MPI::MPI_C, which needs the C language.
  enable_language(C)
  find_package(MPI COMPONENTS C QUIET)
  find_package(PCL 1.10 REQUIRED COMPONENTS common octree kdtree search segmentation)
  add_library(dasp_peers STATIC ${CMAKE_CURRENT_SOURCE_DIR}/tools/peers/peers.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/tools/peers/methods.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/tools/peers/lccp.cpp)
  target_include_directories(dasp_peers PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/tools)
  target_include_directories(dasp_peers SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
  target_link_libraries(dasp_peers PUBLIC dasp::dasp opencv_ximgproc
    PRIVATE pcl_common pcl_octree pcl_kdtree pcl_search pcl_segmentation)
  target_compile_options(dasp_peers PRIVATE ${DASP_WARNINGS})
  # The parts of dasp_sdasp beside its command line (tools/sdasp/); linked like the other tool
  # libraries, only dasp_sdasp uses them.
  add_library(dasp_sdasp_parts STATIC ${CMAKE_CURRENT_SOURCE_DIR}/tools/sdasp/common.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/tools/sdasp/evaluate.cpp)
  target_include_directories(dasp_sdasp_parts PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/tools)
  target_link_libraries(dasp_sdasp_parts PUBLIC dasp::dasp dasp_peers nlohmann_json::nlohmann_json)
  target_compile_options(dasp_sdasp_parts PRIVATE ${DASP_WARNINGS})
  list(APPEND DASP_TOOL_LIBS dasp_peers dasp_sdasp_parts CLI11::CLI11 nlohmann_json::nlohmann_json)
  list(APPEND DASP_TEST_LIBS dasp_peers)  # test/peers_test.cpp
endif()

# dasp-core: the DALIC assignment and feature loops are written to vectorise, but GCC's -O2
# "very cheap" cost model refuses loops of unknown trip count; allow its dynamic model there.
# std::sqrt setting errno and divisions that might raise FP exceptions also keep loops scalar:
# the library reads neither errno nor FP exception flags, and neither flag changes any result.
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  target_compile_options(dasp PRIVATE -fno-math-errno -fno-trapping-math)
endif()
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set_source_files_properties(${CMAKE_CURRENT_SOURCE_DIR}/src/dalic.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/features.cpp ${CMAKE_CURRENT_SOURCE_DIR}/src/density.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/superpoints.cpp ${CMAKE_CURRENT_SOURCE_DIR}/src/connectivity.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/delta_density.cpp ${CMAKE_CURRENT_SOURCE_DIR}/src/sampling.cpp
    PROPERTIES COMPILE_OPTIONS "-fvect-cost-model=dynamic;-fassociative-math;-fno-signed-zeros")
  # The DALIC, superpoint-fit and connectivity kernels (simd.h, run_sums.h) pass GCC vector types
  # between always-inlined helpers; GCC's note that such arguments have another ABI without AVX
  # concerns calls across objects, which never happen here.
  set_property(SOURCE ${CMAKE_CURRENT_SOURCE_DIR}/src/dalic.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/superpoints.cpp ${CMAKE_CURRENT_SOURCE_DIR}/src/connectivity.cpp
    APPEND PROPERTY COMPILE_OPTIONS -Wno-psabi)
endif()
# Benchmarks compare against OpenCV ximgproc SLIC in the same run.
if(DASP_BUILD_BENCHMARKS)
  find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs ximgproc)
  list(APPEND DASP_BENCH_LIBS opencv_ximgproc)
endif()
