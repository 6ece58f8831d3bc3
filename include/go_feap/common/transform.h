// Checks on rigid transforms read from configuration (camera extrinsics).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

namespace go_feap::common {

/// A finite homogeneous rigid transform: last row 0 0 0 1, a rotation (orthonormal within 1e-6,
/// determinant > 0) and a finite translation.
inline bool isRigidTransform(const Eigen::Matrix4d& T) {
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  return T.allFinite() && T.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)) &&
         (R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-6) && R.determinant() > 0.0;
}

/// Metres a camera may sit from the body's origin: a mount on the vehicle. A translation written in
/// millimetres (100 for 0.1 m) put the camera 100 m off, and every frame was mapped there.
constexpr double kMaxMountOffset = 2.0;

/// A rigid transform (isRigidTransform) whose translation is at most kMaxMountOffset: a camera's extrinsic.
inline bool isCameraMount(const Eigen::Matrix4d& T) {
  return isRigidTransform(T) && T.topRightCorner<3, 1>().norm() <= kMaxMountOffset;
}

}  // namespace go_feap::common
