#include "kg/synth/figure.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace kg::synth {

FigureDimensions figure_dimensions(double stature) {
  if (!std::isfinite(stature) || stature < 0.5 || stature > 3.0) {
    std::ostringstream s;
    s << "figure: stature " << stature << " m: expected 0.5 to 3 metres";
    throw std::invalid_argument(s.str());
  }
  const double H = stature;
  FigureDimensions d;
  d.stature = H;
  d.ankle_height = 0.039 * H;
  d.shank = 0.246 * H;  // knee 0.285 H - ankle 0.039 H
  d.thigh = 0.245 * H;  // hip 0.530 H - knee 0.285 H
  d.hip_height = d.ankle_height + d.shank + d.thigh;
  d.hip_half_width = 0.050 * H;
  d.pelvis_drop = 0.020 * H;
  d.heel_back = 0.030 * H;
  d.ball_forward = 0.079 * H;
  d.ball_height = 0.012 * H;
  d.toe_length = 0.043 * H;
  // 0.530 + 0.020 + 0.040 + 0.130 + 0.115 + 0.055 + 0.110 = 1: the top of the head is at H.
  d.spine = 0.040 * H;
  d.chest = 0.130 * H;
  d.neck = 0.115 * H;
  d.head = 0.055 * H;
  d.head_top = 0.110 * H;
  d.clavicle_side = 0.020 * H;
  d.clavicle_up = 0.080 * H;
  d.shoulder_side = 0.090 * H;
  d.shoulder_up = 0.015 * H;
  d.upper_arm = 0.186 * H;
  d.forearm = 0.146 * H;
  d.hand = 0.108 * H;
  return d;
}

Figure make_figure(double stature) {
  using motion::Channel;
  using motion::ChannelKind;
  Figure fig;
  fig.dims = figure_dimensions(stature);
  const FigureDimensions& d = fig.dims;

  auto skeleton = std::make_shared<motion::Skeleton>();
  const std::vector<Channel> zxy{
      {ChannelKind::Zrotation}, {ChannelKind::Xrotation}, {ChannelKind::Yrotation}};
  auto add = [&](const std::string& name, int parent, const Eigen::Vector3d& offset) {
    motion::Joint j;
    j.name = name;
    j.parent = parent;
    j.offset = offset;
    j.channels = zxy;
    return skeleton->add_joint(std::move(j));
  };
  auto end_site = [&](int joint, const Eigen::Vector3d& offset) {
    skeleton->joint_mut(joint).end_sites.push_back(offset);
  };

  {
    motion::Joint root;
    root.name = "Hips";
    root.offset = Eigen::Vector3d(0, d.rest_root_height(), 0);
    root.channels = {{ChannelKind::Xposition}, {ChannelKind::Yposition}, {ChannelKind::Zposition}};
    root.channels.insert(root.channels.end(), zxy.begin(), zxy.end());
    fig.hips = skeleton->add_joint(std::move(root));
  }
  fig.spine = add("Spine", fig.hips, {0, d.spine, 0});
  fig.chest = add("Chest", fig.spine, {0, d.chest, 0});
  fig.neck = add("Neck", fig.chest, {0, d.neck, 0});
  fig.head = add("Head", fig.neck, {0, d.head, 0});
  end_site(fig.head, {0, d.head_top, 0});
  for (Side side : {kLeft, kRight}) {
    const double s = side_sign(side);
    const std::string n = side_name(side);
    fig.shoulder[side] = add(n + "Shoulder", fig.chest, {s * d.clavicle_side, d.clavicle_up, 0});
    fig.arm[side] = add(n + "Arm", fig.shoulder[side], {s * d.shoulder_side, d.shoulder_up, 0});
    fig.forearm[side] = add(n + "ForeArm", fig.arm[side], {0, -d.upper_arm, 0});
    fig.hand[side] = add(n + "Hand", fig.forearm[side], {0, -d.forearm, 0});
    end_site(fig.hand[side], {0, -d.hand, 0});
  }
  for (Side side : {kLeft, kRight}) {
    const double s = side_sign(side);
    const std::string n = side_name(side);
    fig.up_leg[side] = add(n + "UpLeg", fig.hips, {s * d.hip_half_width, -d.pelvis_drop, 0});
    fig.leg[side] = add(n + "Leg", fig.up_leg[side], {0, -d.thigh, 0});
    fig.foot[side] = add(n + "Foot", fig.leg[side], {0, -d.shank, 0});
    fig.toe[side] = add(n + "ToeBase", fig.foot[side], {0, d.ball_height - d.ankle_height, d.ball_forward});
    end_site(fig.toe[side], {0, -d.ball_height, d.toe_length});
  }
  fig.heel_local = Eigen::Vector3d(0, -d.ankle_height, -d.heel_back);
  fig.ankle_local = Eigen::Vector3d::Zero();
  fig.ball_local = Eigen::Vector3d::Zero();
  fig.toe_tip_local = Eigen::Vector3d(0, -d.ball_height, d.toe_length);
  fig.skeleton = std::move(skeleton);
  return fig;
}

}  // namespace kg::synth
