// SceneServer: builds the ground-truth scene and publishes it latched as a cloud of
// occupied voxel centres (scene_cloud, world frame) for rviz.
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "go_feap/ros/params.h"
#include "go_feap/world/scene.h"

namespace go_feap {

class SceneServer : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    ros_params::ParamReader p(pnh);
    std::string frame;
    p.getFrame("simulation/world_frame", frame);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    const world::Scene scene = ros_params::loadScene(pnh, getName());

    sensor_msgs::PointCloud2 cloud;
    cloud.header.frame_id = frame;
    cloud.header.stamp = ros::Time::now();
    sensor_msgs::PointCloud2Modifier mod(cloud);
    mod.setPointCloud2FieldsByString(1, "xyz");
    mod.resize(scene.occupiedCount());
    sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
    const auto& geo = scene.geometry();
    for (std::size_t l = 0; l < scene.occupied.size(); ++l) {
      if (!scene.occupied[l]) continue;
      const common::Vec3 c = geo.indexToCoord(geo.unlinear(l));
      *x = static_cast<float>(c.x());
      *y = static_cast<float>(c.y());
      *z = static_cast<float>(c.z());
      ++x, ++y, ++z;
    }
    pub_ = nh.advertise<sensor_msgs::PointCloud2>("scene_cloud", 1, /*latch=*/true);
    pub_.publish(cloud);
    NODELET_INFO_STREAM(getName() << ": scene '" << scene.name << "' (seed " << scene.seed << "), "
                                  << scene.occupiedCount() << " occupied voxels published");
  }

  ros::Publisher pub_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::SceneServer, nodelet::Nodelet)
