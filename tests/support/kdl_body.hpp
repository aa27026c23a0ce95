// Test and bench support: a body model (kg/body/body_model.hpp) as KDL segments, to check and
// time inverse dynamics against KDL's ChainIdSolver_RNE and TreeIdSolver_RNE (Debian
// liborocos-kdl-dev; include only where KG_HAVE_KDL is defined).
//
// Per joint, in skeleton order: a fixed segment to the joint's origin (its offset with the
// components its position channels replace zeroed; for a root, file_to_world first), one
// TransX/Y/Z segment per position channel, then one RotAxis segment per rotation channel about
// `axis * unit axis`, the last segment carrying the joint's inertia in the joint's frame. KDL's
// joint order is then kg::retime::DynamicsTopology's channel order.
//
//   kg::test::KdlBody k = kg::test::kdl_body(body);
//   KDL::ChainIdSolver_RNE solver(k.chain, KDL::Vector(0, -9.81, 0));   // k.chain: chains only
//   KDL::TreeIdSolver_RNE tree_solver(k.tree, KDL::Vector(0, -9.81, 0));
#pragma once

#include <kdl/chain.hpp>
#include <kdl/tree.hpp>

#include <string>
#include <vector>

#include "kg/body/body_model.hpp"

namespace kg::test {

inline KDL::Vector kdl(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

inline KDL::Rotation kdl(const Eigen::Matrix3d& R) {
  return {R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)};
}

struct KdlBody {
  KDL::Chain chain;  // empty unless every joint's parent is the joint before it (one root)
  KDL::Tree tree{"base"};
  std::vector<std::string> last_segment;  // per joint: the name of the segment carrying its inertia
  std::vector<int> last_chain_segment;    // per joint: that segment's index in `chain`
};

inline KdlBody kdl_body(const body::BodyModel& body) {
  const motion::Skeleton& s = *body.skeleton;
  KdlBody k;
  bool is_chain = true;
  for (int j = 0; j < s.joint_count(); ++j) is_chain = is_chain && s.joint(j).parent == j - 1;
  for (int j = 0; j < s.joint_count(); ++j) {
    const motion::Joint& jt = s.joint(j);
    std::vector<KDL::Joint> joints;
    Eigen::Vector3d offset = jt.offset;
    for (const motion::Channel& c : jt.channels)
      if (!motion::is_rotation(c.kind)) {
        offset[motion::axis_index(c.kind)] = 0;
        const KDL::Joint::JointType t[] = {KDL::Joint::TransX, KDL::Joint::TransY, KDL::Joint::TransZ};
        joints.emplace_back(t[motion::axis_index(c.kind)]);
      }
    for (const motion::Channel& c : jt.channels)
      if (motion::is_rotation(c.kind))
        joints.emplace_back(KDL::Vector::Zero(),
                            kdl(Eigen::Vector3d(jt.axis.col(motion::axis_index(c.kind)))),
                            KDL::Joint::RotAxis);
    const body::SegmentInertia& seg = body.segments[static_cast<std::size_t>(j)];
    const Eigen::Matrix3d& I = seg.inertia;
    const KDL::RigidBodyInertia inertia(
        seg.mass, kdl(seg.com), KDL::RotationalInertia(I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)));
    const KDL::Frame to_origin =
        jt.parent < 0 ? KDL::Frame(kdl(s.file_to_world), kdl(Eigen::Vector3d(s.file_to_world * offset)))
                      : KDL::Frame(kdl(offset));
    std::vector<KDL::Segment> segments;
    std::string name = "j";  // built piecewise: g++ 12 warns falsely on "j" + std::to_string(j)
    name += std::to_string(j);
    name += '_';
    segments.emplace_back(name + "0", KDL::Joint(KDL::Joint::Fixed), to_origin,
                          joints.empty() ? inertia : KDL::RigidBodyInertia::Zero());
    for (std::size_t i = 0; i < joints.size(); ++i)
      segments.emplace_back(name + std::to_string(i + 1), joints[i], KDL::Frame::Identity(),
                            i + 1 == joints.size() ? inertia : KDL::RigidBodyInertia::Zero());
    std::string hook = jt.parent < 0 ? "base" : k.last_segment[static_cast<std::size_t>(jt.parent)];
    for (const KDL::Segment& sg : segments) {
      k.tree.addSegment(sg, hook);
      hook = sg.getName();
      if (is_chain) k.chain.addSegment(sg);
    }
    k.last_segment.push_back(hook);
    k.last_chain_segment.push_back(is_chain ? static_cast<int>(k.chain.getNrOfSegments()) - 1 : -1);
  }
  return k;
}

}  // namespace kg::test
