# Debian's ROS1 bag storage library ships no usable CMake package (docs/design.md
# section 10). Build an imported target by hand. Its headers pull the ROS 2
# flavour of pluginlib, hence the extra include folders. rosbag_storage itself
# links roslz4 and bz2, so compressed bags read without more libraries here.
#
# Debian 12 packages: librosbag-storage-dev libsensor-msgs-dev
# libroscpp-core-dev pluginlib-dev libclass-loader-dev librcpputils-dev
# libament-index-cpp-dev (python3-rosbag for the interoperability test).
set(_rosbag_packages "librosbag-storage-dev libsensor-msgs-dev libroscpp-core-dev pluginlib-dev libclass-loader-dev librcpputils-dev libament-index-cpp-dev")

set(_rosbag_libs rosbag_storage roscpp_serialization rostime cpp_common console_bridge boost_filesystem)
set(_rosbag_paths)
foreach(lib ${_rosbag_libs})
  find_library(RVLIO_LIB_${lib} NAMES ${lib})
  if(NOT RVLIO_LIB_${lib})
    message(FATAL_ERROR "rvlio: library ${lib} not found; install ${_rosbag_packages}")
  endif()
  list(APPEND _rosbag_paths ${RVLIO_LIB_${lib}})
endforeach()

find_path(RVLIO_ROSBAG_INCLUDE rosbag/bag.h)
find_path(RVLIO_SENSOR_MSGS_INCLUDE sensor_msgs/PointCloud2.h)
find_path(RVLIO_PLUGINLIB_INCLUDE pluginlib/class_loader.hpp PATHS /usr/include/pluginlib)
foreach(var RVLIO_ROSBAG_INCLUDE RVLIO_SENSOR_MSGS_INCLUDE RVLIO_PLUGINLIB_INCLUDE)
  if(NOT ${var})
    message(FATAL_ERROR "rvlio: ROS1 bag headers not found (${var}); install ${_rosbag_packages}")
  endif()
endforeach()

add_library(rvlio::rosbag INTERFACE IMPORTED)
set_target_properties(rvlio::rosbag PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${RVLIO_ROSBAG_INCLUDE};${RVLIO_SENSOR_MSGS_INCLUDE};${RVLIO_PLUGINLIB_INCLUDE}"
  INTERFACE_LINK_LIBRARIES "${_rosbag_paths}")
foreach(dir class_loader rcpputils rcutils ament_index_cpp)
  if(EXISTS /usr/include/${dir})
    set_property(TARGET rvlio::rosbag APPEND PROPERTY INTERFACE_INCLUDE_DIRECTORIES /usr/include/${dir})
  endif()
endforeach()
