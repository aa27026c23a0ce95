// The physical character a clip is retimed for (McCann et al. 2006 §3.1, §3.2, §4): each joint's
// segment with its mass, centre of mass and inertia, torque limits per channel, the friction
// coefficient of its contacts and the gravity vector.
//
// A joint's segment is the rigid body moving with the joint's frame (skeleton.hpp): the bone from
// the joint towards its children or End Site. The generalised coordinates are the skeleton's
// channels, each a one-degree-of-freedom joint (a position channel slides, a rotation channel
// turns), so a generalised force per channel is in newtons (position) or newton metres
// (rotation). The root's channels carry no actuator: the environment alone must move the root.
//
//   BodyModel body = ...;   // built by retime.body_model
//   double kg = body.total_mass();
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "kg/motion/skeleton.hpp"

namespace kg::body {

struct SegmentInertia {
  double mass = 0;                                    // kg, >= 0 (0: a massless joint)
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      // metres, in the joint's frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // kg m², about com, joint-frame axes
};

struct BodyModel {
  std::shared_ptr<const motion::Skeleton> skeleton;  // shared, immutable
  std::vector<SegmentInertia> segments{};            // one per joint, skeleton order
  std::vector<std::string> segment_class{};          // per joint: table segment ("thigh"), "" if massless
  // Bounds on each channel's generalised force (N or N m), channel_count() long each;
  // +-infinity where unlimited. Root channels are 0 and 0 (unactuated).
  Eigen::VectorXd torque_min{};
  Eigen::VectorXd torque_max{};
  double friction = 0.5;                     // Coulomb coefficient of every contact
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};  // m/s², world frame (+Y up)

  double total_mass() const {
    double sum = 0;
    for (const SegmentInertia& s : segments) sum += s.mass;
    return sum;
  }
};

}  // namespace kg::body
