# Debian's ROS1 bag storage library ships no usable CMake package (DESIGN.md
# section 9). Build an imported target by hand. Its headers pull the ROS 2
# flavour of pluginlib, hence the extra include folders.
set(_rosbag_libs rosbag_storage roscpp_serialization rostime cpp_common console_bridge boost_filesystem)
set(_rosbag_paths)
foreach(lib ${_rosbag_libs})
  find_library(RVLIO_LIB_${lib} NAMES ${lib} REQUIRED)
  list(APPEND _rosbag_paths ${RVLIO_LIB_${lib}})
endforeach()
find_path(RVLIO_ROSBAG_INCLUDE rosbag/bag.h REQUIRED)
add_library(rvlio::rosbag INTERFACE IMPORTED)
set_target_properties(rvlio::rosbag PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${RVLIO_ROSBAG_INCLUDE}"
  INTERFACE_LINK_LIBRARIES "${_rosbag_paths}")
foreach(dir pluginlib class_loader rcpputils rcutils ament_index_cpp)
  if(EXISTS /usr/include/${dir})
    set_property(TARGET rvlio::rosbag APPEND PROPERTY INTERFACE_INCLUDE_DIRECTORIES /usr/include/${dir})
  endif()
endforeach()
