# The build every ROS package of this workspace shares (dasp_ros, ebslam_ros, edvs_driver): exported
# by ebslam_ros_common as a catkin CFG_EXTRAS file, so
# `find_package(catkin COMPONENTS ebslam_ros_common ...)` brings these in. Targets get C++17, the
# project warnings (errors) and the catkin libraries.

# This file's folder: the source's cmake/ in the devel space, share/ebslam_ros_common/cmake
# installed; nodelet_node.cpp.in lies next to it in both.
set(EBSLAM_ROS_COMMON_CMAKE_DIR ${CMAKE_CURRENT_LIST_DIR})

# Language settings and ROS_PACKAGE_WARNINGS; call right after project().
macro(ros_package_setup)
  set(CMAKE_CXX_STANDARD 17)
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
  set(CMAKE_CXX_EXTENSIONS OFF)
  set(CMAKE_POSITION_INDEPENDENT_CODE ON)
  if(NOT CMAKE_BUILD_TYPE)
    set(CMAKE_BUILD_TYPE RelWithDebInfo)
  endif()
  set(ROS_PACKAGE_WARNINGS -Wall -Wextra -Wpedantic -Werror)
endmacro()

# ros_package_target(<target> [LINK <libs>...] [DEPENDS <targets>...] [DEFINITIONS <defs>...])
# Project warnings, catkin include directories and libraries, the messages and dynamic_reconfigure
# headers built first, plus the given links, build dependencies and compile definitions.
function(ros_package_target target)
  cmake_parse_arguments(ARG "" "" "LINK;DEPENDS;DEFINITIONS" ${ARGN})
  # Libraries pass includes and links on to what links them; executables (and catkin's test
  # targets, linked with the plain signature) keep them.
  get_target_property(type ${target} TYPE)
  if(type MATCHES "LIBRARY")
    target_include_directories(${target} PUBLIC ${catkin_INCLUDE_DIRS})
    target_link_libraries(${target} PUBLIC ${ARG_LINK} ${catkin_LIBRARIES})
  else()
    target_include_directories(${target} PRIVATE ${catkin_INCLUDE_DIRS})
    target_link_libraries(${target} ${ARG_LINK} ${catkin_LIBRARIES})
  endif()
  target_compile_options(${target} PRIVATE ${ROS_PACKAGE_WARNINGS})
  if(catkin_EXPORTED_TARGETS)
    add_dependencies(${target} ${catkin_EXPORTED_TARGETS})
  endif()
  if(TARGET ${PROJECT_NAME}_gencfg)
    add_dependencies(${target} ${PROJECT_NAME}_gencfg)
  endif()
  if(ARG_DEPENDS)
    add_dependencies(${target} ${ARG_DEPENDS})
  endif()
  if(ARG_DEFINITIONS)
    target_compile_definitions(${target} PRIVATE ${ARG_DEFINITIONS})
  endif()
endfunction()

# A test program itself at -O1 (the nodelets and libraries it tests keep -O2): about a quarter
# less compile time for the roscpp-heavy test sources, the same results (no fast-math at any level).
function(ros_package_test_optimisation target)
  target_compile_options(${target} PRIVATE $<$<NOT:$<CONFIG:Debug>>:-O1>)
endfunction()

# ros_package_rostest(<name> <file.test> <sources>... [LINK ...] [DEPENDS ...] [DEFINITIONS ...])
# A rostest whose test node is the gtest program <name> built from <sources>.
function(ros_package_rostest name test_file)
  cmake_parse_arguments(ARG "" "" "LINK;DEPENDS;DEFINITIONS" ${ARGN})
  add_rostest_gtest(${name} ${test_file} ${ARG_UNPARSED_ARGUMENTS})
  ros_package_target(${name} LINK ${ARG_LINK} DEPENDS ${ARG_DEPENDS} DEFINITIONS ${ARG_DEFINITIONS})
  ros_package_test_optimisation(${name})
endfunction()

# ros_package_gtest(<name> <sources>... [LINK ...] [DEPENDS ...] [DEFINITIONS ...])
# A gtest program run without a ROS master.
function(ros_package_gtest name)
  cmake_parse_arguments(ARG "" "" "LINK;DEPENDS;DEFINITIONS" ${ARGN})
  catkin_add_gtest(${name} ${ARG_UNPARSED_ARGUMENTS})
  ros_package_target(${name} LINK ${ARG_LINK} gtest_main DEPENDS ${ARG_DEPENDS}
    DEFINITIONS ${ARG_DEFINITIONS})
  ros_package_test_optimisation(${name})
endfunction()

# nodelet_node(<target> NODELET <package/Class> [NAME <node name>])
# The standalone node of a nodelet: executable <target> (installed into the package's bin folder)
# whose main, generated from nodelet_node.cpp.in, loads the nodelet into its own process under the
# node's name (default: <target> without "_node"), with the node's remappings and arguments. Same
# topics, parameters and services as the nodelet in a manager; a nodelet that fails to start
# (ebslam_ros_common/ros_param_helpers.h) ends the node with exit status 1.
function(nodelet_node target)
  cmake_parse_arguments(ARG "" "NODELET;NAME" "" ${ARGN})
  if(NOT ARG_NODELET)
    message(FATAL_ERROR "nodelet_node(${target}): NODELET <package/Class> missing")
  endif()
  set(NODE_NAME ${ARG_NAME})
  if(NOT NODE_NAME)
    string(REGEX REPLACE "_node$" "" NODE_NAME ${target})
  endif()
  set(NODELET_TYPE ${ARG_NODELET})
  set(source ${CMAKE_CURRENT_BINARY_DIR}/nodelet_nodes/${target}.cpp)
  configure_file(${EBSLAM_ROS_COMMON_CMAKE_DIR}/nodelet_node.cpp.in ${source} @ONLY)
  add_executable(${target} ${source})
  ros_package_target(${target})
  install(TARGETS ${target} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endfunction()
