# ctest: configures the on-board tree (SWEEPMAP_ONBOARD) with PCL, Ceres, OctoMap and
# nlohmann-json made unfindable, and checks its link graph (cmake --graphviz): the three
# on-board executables are there, and nothing links PCL, Ceres, OctoMap, nlohmann-json or a
# library of the full build only (calib, mapping, processes, tools_*).
# Usage: cmake -DSOURCE_DIR=<repo> -DWORK_DIR=<scratch folder> -P check_onboard_config.cmake
cmake_policy(VERSION 3.22)
foreach(var SOURCE_DIR WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "check_onboard_config: -D${var}= missing")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(
  COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR} -DSWEEPMAP_ONBOARD=ON
          -DCMAKE_DISABLE_FIND_PACKAGE_PCL=ON -DCMAKE_DISABLE_FIND_PACKAGE_Ceres=ON
          -DCMAKE_DISABLE_FIND_PACKAGE_octomap=ON -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON
          --graphviz=${WORK_DIR}/graph/onboard.dot
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "check_onboard_config: the on-board configure failed (${rc}):\n${out}")
endif()
file(STRINGS ${WORK_DIR}/graph/onboard.dot nodes REGEX "label = \"")
set(labels)
foreach(line ${nodes})
  string(REGEX MATCH "label = \"([^\"]+)\"" _ "${line}")
  list(APPEND labels "${CMAKE_MATCH_1}")
endforeach()
foreach(exe sweepmap-motor sweepmap-lidar sweepmap-odometry)
  if(NOT exe IN_LIST labels)
    message(FATAL_ERROR "check_onboard_config: ${exe} is not in the on-board build; targets: ${labels}")
  endif()
endforeach()
set(bad)
foreach(label ${labels})
  string(TOLOWER "${label}" lower)
  if(lower MATCHES "pcl|ceres|octomap|octomath|nlohmann|^calib$|^mapping$|^processes$|^tools_")
    list(APPEND bad "${label}")
  endif()
endforeach()
if(bad)
  message(FATAL_ERROR "check_onboard_config: the on-board build links ${bad}")
endif()
list(LENGTH labels n)
message(STATUS "check_onboard_config: ${n} targets and libraries, none of PCL, Ceres, OctoMap")
