// URDF robots (urdf.hpp): urdfdom reads the model, tinyxml2 the same text again for what urdfdom
// does not keep (the file's order of joints and the line of each element, for messages).
#include "kg/io/urdf.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include <console_bridge/console.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/text.hpp"

namespace kg::io {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// urdfdom says what is wrong through console_bridge; this keeps its errors for our message.
class ErrorCollector : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first_error.empty()) first_error = text;
  }
  std::string first_error;
};

// Elements by name with their lines, and the joints in the file's order.
struct FileIndex {
  std::unordered_map<std::string, int> joint_line, link_line;
  std::vector<std::string> joints_in_order;
  std::string robot_name;
};

FileIndex index_file(const std::string& path, const std::string& text) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) {
    // ErrorStr() is "Error=NAME ErrorID=N (0xN) Line number=L: detail"; the name and detail say it.
    std::string what = doc.ErrorIDToName(doc.ErrorID());
    const std::string full = doc.ErrorStr() ? doc.ErrorStr() : "";
    if (const std::size_t at = full.find(": ", full.find("Line number=")); at != std::string::npos)
      what += ": " + full.substr(at + 2);
    throw kg::Error("not a URDF file: malformed XML (" + text::excerpt(what, 120) + ")",
                    {path, doc.ErrorLineNum()});
  }
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) {
    const tinyxml2::XMLElement* first = doc.FirstChildElement();
    throw kg::Error(std::string("not a URDF file: expected a <robot> element, got ") +
                        (first ? "<" + text::excerpt(first->Name()) + ">" : std::string("no element")),
                    {path, first ? first->GetLineNum() : 1});
  }
  FileIndex index;
  if (const char* name = robot->Attribute("name")) index.robot_name = name;
  for (const tinyxml2::XMLElement* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    const char* name = e->Attribute("name");
    if ((tag == "joint" || tag == "link") && (!name || !*name))
      throw kg::Error("<" + tag + "> without a name: expected a name=\"...\" attribute",
                      {path, e->GetLineNum()});
    if (!name) continue;
    if (tag == "joint") {
      if (index.joint_line.emplace(name, e->GetLineNum()).second) index.joints_in_order.push_back(name);
    } else if (tag == "link") {
      index.link_line.emplace(name, e->GetLineNum());
    }
  }
  return index;
}

// The line of the first joint or link that urdfdom's message names ("[knee]" or "'knee'"), so
// that the message points at the element at fault.
int line_named_in(const std::string& message, const FileIndex& index) {
  for (std::size_t i = 0; i < message.size(); ++i) {
    const char open = message[i];
    const char close = open == '[' ? ']' : open == '\'' ? '\'' : open == '"' ? '"' : 0;
    if (!close) continue;
    const std::size_t end = message.find(close, i + 1);
    if (end == std::string::npos) break;
    const std::string name = message.substr(i + 1, end - i - 1);
    if (auto j = index.joint_line.find(name); j != index.joint_line.end()) return j->second;
    if (auto l = index.link_line.find(name); l != index.link_line.end()) return l->second;
    i = end;
  }
  return 0;
}

urdf::ModelInterfaceSharedPtr parse_model(const std::string& path, const std::string& text,
                                          const FileIndex& index) {
  // console_bridge's handler is process-wide: one parse at a time.
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  ErrorCollector collector;
  console_bridge::useOutputHandler(&collector);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    collector.first_error = e.what();
  }
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    std::string why = collector.first_error.empty() ? "urdfdom refused it" : collector.first_error;
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    throw kg::Error("not a valid URDF robot: " + text::excerpt(why, 300), {path, line_named_in(why, index)});
  }
  return model;
}

Eigen::Matrix3d rotation_of(const urdf::Rotation& r) {
  Eigen::Quaterniond q(r.w, r.x, r.y, r.z);
  if (!(q.norm() > 0.0) || !std::isfinite(q.norm())) return Eigen::Matrix3d::Identity();
  return q.normalized().toRotationMatrix();
}

Eigen::Vector3d vector_of(const urdf::Vector3& v) {
  return {v.x, v.y, v.z};
}

// A right-handed orthonormal frame whose first column is `x` (unit).
Eigen::Matrix3d frame_with_first_axis(const Eigen::Vector3d& x) {
  const Eigen::Vector3d helper = std::abs(x.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d y = x.cross(helper).normalized();
  Eigen::Matrix3d m;
  m.col(0) = x;
  m.col(1) = y;
  m.col(2) = x.cross(y);
  return m;
}

bool finite(const Eigen::Vector3d& v) {
  return v.allFinite();
}

}  // namespace

const char* to_string(RobotJointType type) {
  switch (type) {
    case RobotJointType::Revolute:
      return "revolute";
    case RobotJointType::Continuous:
      return "continuous";
    case RobotJointType::Prismatic:
      return "prismatic";
  }
  return "?";
}

double Robot::total_mass() const {
  double m = 0;
  for (const RobotLink& l : links) m += l.mass;
  return m;
}

int Robot::find_dof(const std::string& dof_name) const {
  for (std::size_t i = 0; i < dofs.size(); ++i)
    if (dofs[i].name == dof_name) return static_cast<int>(i);
  return -1;
}

const RobotLink* Robot::find_link(const std::string& link_name) const {
  for (const RobotLink& l : links)
    if (l.name == link_name) return &l;
  return nullptr;
}

Robot read_urdf(const std::string& path) {
  return parse_urdf(read_input_file(path, "URDF file"), path);
}

Robot parse_urdf(const std::string& text, const std::string& path) {
  const FileIndex index = index_file(path, text);
  const urdf::ModelInterfaceSharedPtr model = parse_model(path, text, index);
  const urdf::LinkConstSharedPtr root = model->getRoot();
  if (!root) throw kg::Error("not a valid URDF robot: no root link", {path});

  Robot robot;
  robot.name = model->getName();
  robot.path = path;
  auto skeleton = std::make_shared<motion::Skeleton>();
  skeleton->file_to_world = z_up_to_y_up();

  // Each link's rest rotation and skeleton joint, filled as the tree is placed.
  std::unordered_map<std::string, int> joint_of_link;
  std::vector<Eigen::Matrix3d> rest_rotation;
  auto add_link = [&](const urdf::Link& link, int joint, const Eigen::Matrix3d& W) {
    joint_of_link[link.name] = joint;
    if (static_cast<int>(rest_rotation.size()) <= joint)
      rest_rotation.resize(static_cast<std::size_t>(joint) + 1);
    rest_rotation[static_cast<std::size_t>(joint)] = W;
    RobotLink out{.name = link.name, .joint = joint, .rest_rotation = W};
    auto line = index.link_line.find(link.name);
    out.line = line == index.link_line.end() ? 0 : line->second;
    if (link.inertial) {
      const urdf::Inertial& in = *link.inertial;
      const Eigen::Matrix3d R = rotation_of(in.origin.rotation);
      Eigen::Matrix3d I;
      I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
      out.mass = in.mass;
      out.com = W * vector_of(in.origin.position);
      out.inertia = W * R * I * R.transpose() * W.transpose();
      if (!std::isfinite(in.mass) || in.mass < 0 || !finite(out.com) || !out.inertia.allFinite())
        throw kg::Error("link " + text::excerpt(link.name) +
                            ": its <inertial> mass must be finite and >= 0 and its origin and inertia finite",
                        {path, out.line});
    }
    robot.links.push_back(std::move(out));
  };

  using motion::ChannelKind;
  skeleton->add_joint(motion::Joint{.name = root->name,
                                    .parent = -1,
                                    .channels = {{ChannelKind::Xposition},
                                                 {ChannelKind::Yposition},
                                                 {ChannelKind::Zposition},
                                                 {ChannelKind::Zrotation},
                                                 {ChannelKind::Yrotation},
                                                 {ChannelKind::Xrotation}}});
  add_link(*root, 0, Eigen::Matrix3d::Identity());

  // Joints in the file's order, a joint waiting until its parent link is placed (a file may list
  // a child before its parent); a pass that places none means the rest hang off no placed link,
  // which urdfdom has already refused.
  std::vector<std::string> pending = index.joints_in_order;
  while (!pending.empty()) {
    std::vector<std::string> waiting;
    for (const std::string& name : pending) {
      const urdf::JointConstSharedPtr joint = model->getJoint(name);
      if (!joint) continue;
      const auto parent = joint_of_link.find(joint->parent_link_name);
      if (parent == joint_of_link.end()) {
        waiting.push_back(name);
        continue;
      }
      const int line = index.joint_line.at(name);
      const urdf::LinkConstSharedPtr child = model->getLink(joint->child_link_name);
      if (!child) throw kg::Error("joint " + text::excerpt(name) + ": no child link", {path, line});
      const Eigen::Matrix3d& Wp = rest_rotation[static_cast<std::size_t>(parent->second)];
      const Eigen::Vector3d xyz = vector_of(joint->parent_to_joint_origin_transform.position);
      const Eigen::Matrix3d W = Wp * rotation_of(joint->parent_to_joint_origin_transform.rotation);
      if (!finite(xyz))
        throw kg::Error("joint " + text::excerpt(name) + ": its origin is not finite", {path, line});

      motion::Joint j{.name = name, .parent = parent->second, .offset = Wp * xyz};
      RobotDof dof{.name = name, .line = line};
      Eigen::Vector3d axis = vector_of(joint->axis);
      const bool moves = joint->type == urdf::Joint::REVOLUTE || joint->type == urdf::Joint::CONTINUOUS ||
                         joint->type == urdf::Joint::PRISMATIC;
      if (joint->type == urdf::Joint::FLOATING || joint->type == urdf::Joint::PLANAR) {
        throw kg::Error("joint " + text::excerpt(name) + " is " +
                            (joint->type == urdf::Joint::FLOATING ? "floating" : "planar") +
                            ": only the root link floats; expected revolute, continuous, prismatic or fixed",
                        {path, line});
      }
      if (moves) {
        if (!finite(axis) || axis.norm() < 1e-12)
          throw kg::Error("joint " + text::excerpt(name) + ": its <axis> must be a non-zero finite vector",
                          {path, line});
        axis = (W * axis).normalized();
        dof.type = joint->type == urdf::Joint::REVOLUTE     ? RobotJointType::Revolute
                   : joint->type == urdf::Joint::CONTINUOUS ? RobotJointType::Continuous
                                                            : RobotJointType::Prismatic;
        if (dof.type == RobotJointType::Continuous) {
          dof.lower = -kInf;
          dof.upper = kInf;
        } else {
          if (!joint->limits)
            throw kg::Error("joint " + text::excerpt(name) + " is " + to_string(dof.type) +
                                " without <limit>: expected lower and upper",
                            {path, line});
          dof.lower = joint->limits->lower;
          dof.upper = joint->limits->upper;
          if (!std::isfinite(dof.lower) || !std::isfinite(dof.upper) || dof.lower > dof.upper)
            throw kg::Error("joint " + text::excerpt(name) +
                                ": expected finite limits with lower <= upper, got " +
                                text::significant(dof.lower) + " .. " + text::significant(dof.upper),
                            {path, line});
        }
        if (joint->limits) {
          dof.velocity = joint->limits->velocity;
          dof.effort = joint->limits->effort;
          if (!std::isfinite(dof.velocity) || dof.velocity < 0 || !std::isfinite(dof.effort) ||
              dof.effort < 0)
            throw kg::Error("joint " + text::excerpt(name) + ": expected velocity and effort limits >= 0",
                            {path, line});
        }
        j.axis = frame_with_first_axis(axis);
        if (dof.type == RobotJointType::Prismatic) {
          int k = 0;
          axis.cwiseAbs().maxCoeff(&k);
          if (std::abs(std::abs(axis[k]) - 1.0) > 1e-9)
            throw kg::Error(
                "joint " + text::excerpt(name) +
                    " is prismatic along a direction that is not an axis of the base frame at rest; "
                    "only such prismatic joints can be moved yet",
                {path, line});
          dof.sign = axis[k] > 0 ? 1.0 : -1.0;
          dof.offset = j.offset[k];
          const double a = dof.offset + dof.sign * dof.lower, b = dof.offset + dof.sign * dof.upper;
          j.channels = {{static_cast<ChannelKind>(k), std::min(a, b), std::max(a, b)}};
        } else {
          j.channels = {{ChannelKind::Xrotation, dof.lower, dof.upper}};
        }
      }
      const int index_in_skeleton = skeleton->add_joint(std::move(j));
      if (moves) {
        dof.joint = index_in_skeleton;
        dof.channel = skeleton->joint(index_in_skeleton).first_channel;
        robot.dofs.push_back(std::move(dof));
      }
      add_link(*child, index_in_skeleton, W);
    }
    if (waiting.size() == pending.size()) {
      throw kg::Error("joint " + text::excerpt(waiting.front()) +
                          " hangs off no link reachable from the root " + text::excerpt(root->name),
                      {path, index.joint_line.at(waiting.front())});
    }
    pending = std::move(waiting);
  }
  if (robot.links.size() != model->links_.size()) {
    for (const auto& [name, link] : model->links_)
      if (!joint_of_link.count(name))
        throw kg::Error(
            "link " + text::excerpt(name) + " is not connected to the root " + text::excerpt(root->name),
            {path, index.link_line.count(name) ? index.link_line.at(name) : 0});
  }
  // The links in skeleton joint order (add_link ran in that order: the root, then each child).
  robot.skeleton = std::move(skeleton);
  return robot;
}

ImportedMotion import_urdf(const std::string& path, const ImportOptions& options) {
  options.validate();
  if (options.units != "auto" && options.units != "m")
    throw std::invalid_argument(text::shown_path(path) +
                                ": a URDF is in metres; expected units auto or m, got " +
                                text::excerpt(options.units));
  if (options.up != "auto" && options.up != "z" && options.up != "y")
    throw std::invalid_argument(text::shown_path(path) + ": expected up auto, z or y, got " +
                                text::excerpt(options.up));
  Robot robot = read_urdf(path);
  auto skeleton = std::make_shared<motion::Skeleton>(*robot.skeleton);
  if (options.up == "y") skeleton->file_to_world = Eigen::Matrix3d::Identity();
  ImportedMotion out;
  out.motion.skeleton = skeleton;
  out.motion.values = motion::FrameMatrix::Zero(1, skeleton->channel_count());
  out.motion.fps = options.fps > 0 ? options.fps : 30.0;
  out.motion.name = std::filesystem::path(path).stem().string();
  int counts[3] = {0, 0, 0};
  for (const RobotDof& d : robot.dofs) ++counts[static_cast<int>(d.type)];
  char mass[32];
  std::snprintf(mass, sizeof mass, "%.2f", robot.total_mass());
  out.notes.push_back(
      std::filesystem::path(path).filename().string() + ": URDF robot '" + robot.name + "', " +
      std::to_string(robot.links.size()) + " links, " + std::to_string(robot.dofs.size()) +
      " degrees of freedom (" + std::to_string(counts[0]) + " revolute, " + std::to_string(counts[1]) +
      " continuous, " + std::to_string(counts[2]) + " prismatic), " + mass + " kg; metres; " +
      (options.up == "y" ? "Y up (up=y)" : "Z up (REP 103; set up=y for a file that is Y up)") +
      "; the root link '" + skeleton->joint(0).name + "' floats; one frame, every joint at zero");
  return out;
}

}  // namespace kg::io
