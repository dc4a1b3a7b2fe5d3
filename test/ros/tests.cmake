# fragg_map_ros: converters and parameters, plain gtests (no roscore needed).
if(FRAGG_HAVE_ROS)
  fragg_add_test(ros_cloud_from_msg_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/cloud_from_msg_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_map_to_msgs_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/block_markers_test.cpp
            ${CMAKE_CURRENT_LIST_DIR}/map_msgs_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_server_params_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/server_params_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  fragg_add_test(ros_server_parts_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/server_parts_test.cpp
    LIBS fragg_map_ros
    LABELS ros)
  target_compile_definitions(ros_server_params_test PRIVATE
    FRAGG_PYTHON3="/usr/bin/python3"
    FRAGG_YAML_TO_XMLRPC="${CMAKE_CURRENT_LIST_DIR}/yaml_to_xmlrpc.py"
    FRAGG_CONFIG_DIR="${PROJECT_SOURCE_DIR}/config")
endif()

# rostests of the map server (the nodelet) on the smoke bag.
if(FRAGG_HAVE_ROS AND FRAGG_SMOKE_BAG)
  find_package(rostest REQUIRED)
  add_rostest(${CMAKE_CURRENT_LIST_DIR}/../rostest/map_server_smoke.test
    ARGS bag:=${FRAGG_SMOKE_BAG} cli:=${FRAGG_BIN_DIR}/fragg_map
         tmp:=${CMAKE_CURRENT_BINARY_DIR}/tmp/map_server_smoke)
endif()
