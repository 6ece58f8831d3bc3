# Fails when a core source or header includes a ROS header. Run with
# -DFILES=<|-separated list> -DROOT=<source dir> -DSTAMP=<stamp file to touch on success>.
string(REPLACE "|" ";" FILES "${FILES}")
foreach(f ${FILES})
  if(NOT IS_ABSOLUTE "${f}")
    set(f "${ROOT}/${f}")
  endif()
  file(STRINGS "${f}" hits REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"](ros|nodelet|pluginlib|tf2_ros|sensor_msgs|nav_msgs|geometry_msgs|std_msgs|visualization_msgs|cv_bridge|image_transport|message_filters|rosbag|go_feap/ros)/")
  if(hits)
    message(FATAL_ERROR "${f}: the ROS-free core must not include ROS headers: ${hits}")
  endif()
endforeach()
file(TOUCH "${STAMP}")
