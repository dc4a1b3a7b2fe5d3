# Fuzz entry functions (test/fuzz/fuzz_<target>.cpp): the corpus replay test runs all of them in
# every build (CI replays the committed corpora); with FRAGG_FUZZ=ON each also becomes a
# libFuzzer binary, fragg_fuzz_<target>, linked with only what its reader needs (the readers of
# point and pose files do not need the map, so they build and start fuzzing first).
set(_fuzz_dir ${CMAKE_CURRENT_LIST_DIR})
# target | entry function | what it links (readers: the readers' sources alone; map: the core)
set(_fuzz_table
  "fgm|fgm|map" "scan|scan|readers" "pcd|pcd|readers" "ply|ply|readers" "xyz|xyz|readers"
  "kitti_bin|kittiBin|readers" "scan_graph|scanGraph|readers" "poses|poses|readers"
  "waypoints|waypoints|readers" "obj|obj|readers" "insert|insertScan|map")

# The PointCloud2 target: with ROS through fragg_map_ros; without catkin when Debian's ROS
# headers and serialisation libraries are found (the converter compiled in).
set(_fuzz_ros_libs "")
set(_fuzz_ros_sources "")
if(FRAGG_HAVE_ROS)
  set(_fuzz_ros_libs fragg_map_ros)
else()
  find_path(FRAGG_ROS_MSGS_INCLUDE_DIR sensor_msgs/PointCloud2.h)
  find_library(FRAGG_ROSCPP_SERIALIZATION_LIB roscpp_serialization)
  find_library(FRAGG_ROSTIME_LIB rostime)
  find_library(FRAGG_CPP_COMMON_LIB cpp_common)
  if(FRAGG_ROS_MSGS_INCLUDE_DIR AND FRAGG_ROSCPP_SERIALIZATION_LIB AND FRAGG_ROSTIME_LIB AND
     FRAGG_CPP_COMMON_LIB)
    set(_fuzz_ros_libs ${FRAGG_ROSCPP_SERIALIZATION_LIB} ${FRAGG_ROSTIME_LIB}
      ${FRAGG_CPP_COMMON_LIB})
    set(_fuzz_ros_sources ${PROJECT_SOURCE_DIR}/src/ros/cloud_from_msg.cpp)
  endif()
endif()
if(_fuzz_ros_libs)
  list(APPEND _fuzz_table "cloud_msg|cloudMsg|ros")
else()
  message(STATUS "fragg_map: no ROS message headers: no PointCloud2 fuzz target")
endif()

# fuzz_target_setup(TARGET KIND): the ROS message flag, include folders and libraries of KIND.
function(fuzz_target_setup target kind)
  if(_fuzz_ros_libs)
    target_compile_definitions(${target} PRIVATE FRAGG_FUZZ_HAVE_ROS_MSGS=1)
    if(NOT FRAGG_HAVE_ROS)
      target_include_directories(${target} SYSTEM PRIVATE ${FRAGG_ROS_MSGS_INCLUDE_DIR})
    endif()
  endif()
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR}/include)
  target_link_libraries(${target} Eigen3::Eigen)
  if(kind STREQUAL "map")
    target_link_libraries(${target} fragg_map_core ZLIB::ZLIB)
  elseif(kind STREQUAL "readers")
    target_link_libraries(${target} fragg_fuzz_io_lib)
  elseif(kind STREQUAL "ros")
    target_link_libraries(${target} ${_fuzz_ros_libs})
  endif()
endfunction()

set(_fuzz_sources ${_fuzz_dir}/fuzz_registry.cpp ${_fuzz_dir}/fuzz_util.cpp
  ${_fuzz_dir}/insert_input.cpp)
foreach(_row ${_fuzz_table})
  string(REPLACE "|" ";" _row "${_row}")
  list(GET _row 0 _name)
  list(APPEND _fuzz_sources ${_fuzz_dir}/fuzz_${_name}.cpp)
endforeach()
fragg_add_test(fragg_fuzz_corpus_test
  SOURCES ${_fuzz_dir}/corpus_replay_test.cpp ${_fuzz_dir}/regressions_test.cpp ${_fuzz_sources}
          ${_fuzz_ros_sources}
  LIBS fragg_map_core fragg_map_geometry fragg_map_planning ${_fuzz_ros_libs} ZLIB::ZLIB
  LABELS fuzz)
target_compile_definitions(fragg_fuzz_corpus_test PRIVATE
  FRAGG_FUZZ_CORPUS="${_fuzz_dir}/corpus")
fuzz_target_setup(fragg_fuzz_corpus_test none)

if(FRAGG_FUZZ)
  # The readers without the map: the dataset readers, kept-scan records, waypoints and OBJ meshes
  # with what they use of the core, geometry and planning.
  include(${PROJECT_SOURCE_DIR}/src/io/sources.cmake)  # FRAGG_IO_SOURCES
  set(_src ${PROJECT_SOURCE_DIR}/src)
  add_library(fragg_fuzz_io_lib STATIC ${FRAGG_IO_SOURCES} ${_src}/core/atomic_file.cpp
    ${_src}/core/byte_io.cpp ${_src}/core/scan_codec.cpp ${_src}/core/sensor_model.cpp
    ${_src}/core/lidar_beams.cpp
    ${_src}/planning/waypoint_file.cpp ${_src}/geometry/obj_file.cpp
    ${_src}/geometry/triangle_mesh.cpp ${_src}/geometry/mesh_bvh.cpp
    ${_src}/planning/collision_shape.cpp)
  target_include_directories(fragg_fuzz_io_lib PUBLIC ${PROJECT_SOURCE_DIR}/include)
  target_link_libraries(fragg_fuzz_io_lib PUBLIC Eigen3::Eigen PRIVATE ZLIB::ZLIB fmt::fmt)
  fragg_target_flags(fragg_fuzz_io_lib)
  foreach(_row ${_fuzz_table})
    string(REPLACE "|" ";" _row "${_row}")
    list(GET _row 0 _name)
    list(GET _row 1 _entry)
    list(GET _row 2 _kind)
    set(_extra "")
    if(_kind STREQUAL "ros")
      set(_extra ${_fuzz_ros_sources})
    endif()
    if(_name STREQUAL "insert")
      list(APPEND _extra ${_fuzz_dir}/insert_input.cpp)
    endif()
    add_executable(fragg_fuzz_${_name} ${_fuzz_dir}/fuzz_main.cpp ${_fuzz_dir}/fuzz_util.cpp
      ${_fuzz_dir}/fuzz_${_name}.cpp ${_extra})
    target_compile_definitions(fragg_fuzz_${_name} PRIVATE FRAGG_FUZZ_ENTRY=${_entry})
    target_link_options(fragg_fuzz_${_name} PRIVATE -fsanitize=fuzzer)
    target_link_libraries(fragg_fuzz_${_name} ZLIB::ZLIB)
    fuzz_target_setup(fragg_fuzz_${_name} ${_kind})
    set_target_properties(fragg_fuzz_${_name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY
      ${CMAKE_BINARY_DIR}/fuzz)
    fragg_target_flags(fragg_fuzz_${_name})
  endforeach()
endif()
