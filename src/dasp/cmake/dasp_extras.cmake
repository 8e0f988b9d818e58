# Extra dependencies and flags of the dasp library, tools, benchmarks and tests.
# dasp-core: the DALIC assignment and feature loops are written to vectorise, but GCC's -O2
# "very cheap" cost model refuses loops of unknown trip count; allow its dynamic model there.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set_source_files_properties(${CMAKE_CURRENT_SOURCE_DIR}/src/dalic.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/features.cpp ${CMAKE_CURRENT_SOURCE_DIR}/src/superpoints.cpp
    PROPERTIES COMPILE_OPTIONS "-fvect-cost-model=dynamic")
endif()
# Benchmarks compare against OpenCV ximgproc SLIC in the same run.
if(DASP_BUILD_BENCHMARKS)
  find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs ximgproc)
  list(APPEND DASP_BENCH_LIBS opencv_ximgproc)
endif()
