// Contact files (contacts.hpp): YAML -> Contacts with joint names resolved, every error at
// file:line:column with the dotted key path.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/base/yaml_reader.hpp"
#include "kg/motion/frame_time.hpp"
#include "kg/retime/contacts.hpp"

namespace kg::retime {

namespace {

using kg::Error;
using kg::SourceLocation;

class Reader : public kg::YamlReader {
 public:
  Reader(std::string file, const motion::Motion& motion) : YamlReader(std::move(file)), motion_(motion) {}

  Contacts read(const std::string& source) {
    const YAML::Node root = load(source, "empty contact file (expected 'version: 1')");
    if (!root.IsMap()) fail("a contact file must be a map (version, patches)", root.Mark());
    check_keys(root, "", {"version", "doc", "patches"});
    if (!root["version"]) throw Error("missing 'version: 1'", {path(), 1, 1});
    const int version = integer(root["version"], "version");
    if (version != kContactFormatVersion)
      fail("unsupported version " + std::to_string(version) + " (this reads version 1)",
           root["version"].Mark());
    if (root["doc"]) text(root["doc"], "doc");
    const YAML::Node ps = root["patches"];
    if (!ps) throw Error("missing 'patches' (a list of contact patches)", {path(), 1, 1});
    if (!ps.IsSequence()) fail("patches: expected a list", ps.Mark());
    std::vector<ContactPatch> patches;
    std::vector<std::vector<std::pair<int, int>>> ranges;
    int index = 0;
    for (const YAML::Node& p : ps) {
      ranges.emplace_back();
      patches.push_back(patch(p, "patches[" + std::to_string(index++) + "]", patches, ranges.back()));
    }
    std::size_t vertices = 0;
    for (const ContactPatch& p : patches) vertices += p.vertices.size();
    std::vector<std::vector<bool>> active(static_cast<std::size_t>(motion_.frame_count()),
                                          std::vector<bool>(vertices, false));
    std::size_t first = 0;
    for (std::size_t p = 0; p < patches.size(); ++p) {
      for (const auto& [a, b] : ranges[p])
        for (int f = a; f <= b; ++f)
          for (std::size_t v = 0; v < patches[p].vertices.size(); ++v)
            active[static_cast<std::size_t>(f)][first + v] = true;
      first += patches[p].vertices.size();
    }
    Contacts c = assemble_contacts(motion_, std::move(patches), active);
    c.source = path();
    return c;
  }

 private:
  int joint(const YAML::Node& n, const std::string& what) const {
    const std::string name = text(n, what);
    const motion::Skeleton& sk = *motion_.skeleton;
    const int j = sk.find_joint(name);
    if (j >= 0) return j;
    std::string msg = what + ": unknown joint " + text::in_quotes(name);
    const std::string near = motion::nearest_joint_name(sk, name);
    if (!near.empty()) msg += " (did you mean " + text::in_quotes(near) + "?)";
    fail(msg, n.Mark());
  }

  Eigen::Vector3d vertex(const YAML::Node& n, const std::string& what) const {
    if (!n.IsSequence() || n.size() != 3)
      fail(what + ": expected [x, y, z] (metres, in the joint's frame)", n.Mark());
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = number(n[static_cast<std::size_t>(i)], what);
    return v;
  }

  // One [first, last] range in frames (or seconds when `seconds`).
  std::pair<int, int> range(const YAML::Node& n, const std::string& what, bool seconds) const {
    if (!n.IsSequence() || n.size() != 2)
      fail(what + (seconds ? ": expected [first, last] in seconds" : ": expected [first, last] frames"),
           n.Mark());
    int ends[2];
    for (std::size_t i = 0; i < 2; ++i) {
      const YAML::Node x = n[i];
      if (seconds) {
        const double t = number(x, what);
        if (t < 0) fail(what + ": a time must be >= 0 s", x.Mark());
        try {
          ends[i] = motion::seconds_to_frame(t, motion_.fps, motion_.frame_count());
        } catch (const std::out_of_range& e) {
          fail(what + ": " + e.what(), x.Mark());
        }
      } else {
        ends[i] = integer(x, what);
      }
    }
    if (ends[0] > ends[1])
      fail(
          what + ": the range [" + std::to_string(ends[0]) + ", " + std::to_string(ends[1]) + "] is reversed",
          n.Mark());
    const int last = motion_.frame_count() - 1;
    if (ends[0] < 0 || ends[1] > last)
      fail(what + ": frames [" + std::to_string(ends[0]) + ", " + std::to_string(ends[1]) +
               "] are outside the clip (frames 0.." + std::to_string(last) + ")",
           n.Mark());
    return {ends[0], ends[1]};
  }

  ContactPatch patch(const YAML::Node& n, const std::string& path, const std::vector<ContactPatch>& before,
                     std::vector<std::pair<int, int>>& ranges) const {
    if (!n.IsMap()) fail(path + ": expected a map {name, joint, vertices, frames or times}", n.Mark());
    check_keys(n, path, {"name", "joint", "vertices", "frames", "times"});
    if (!n["joint"]) fail(path + ": missing 'joint'", n.Mark());
    ContactPatch p;
    const int j = joint(n["joint"], path + ".joint");
    p.name = n["name"] ? text(n["name"], path + ".name") : motion_.skeleton->joint(j).name;
    for (const ContactPatch& other : before)
      if (other.name == p.name)
        fail(path + ".name: a patch named '" + p.name + "' is already defined" +
                 (n["name"] ? "" : " (name the patches apart)"),
             (n["name"] ? n["name"] : n).Mark());
    const YAML::Node vs = n["vertices"];
    if (!vs) fail(path + ": missing 'vertices' (a list of [x, y, z] in the joint's frame)", n.Mark());
    if (!vs.IsSequence() || vs.size() == 0)
      fail(path + ".vertices: expected a non-empty list of [x, y, z] (metres)", vs.Mark());
    for (std::size_t i = 0; i < vs.size(); ++i)
      p.vertices.push_back({j, vertex(vs[i], path + ".vertices[" + std::to_string(i) + "]")});
    if (n["frames"] && n["times"])
      fail(path + ": give one of 'frames' and 'times', not both", n["times"].Mark());
    const bool seconds = !n["frames"];
    const YAML::Node rs = seconds ? n["times"] : n["frames"];
    if (!rs) fail(path + ": missing 'frames' (or 'times'): when the patch touches", n.Mark());
    const std::string what = path + (seconds ? ".times" : ".frames");
    if (!rs.IsSequence() || rs.size() == 0)
      fail(what + ": expected a list of [first, last] ranges", rs.Mark());
    if (rs[0].IsScalar()) {
      ranges.push_back(range(rs, what, seconds));  // one range written flat: [first, last]
    } else {
      for (std::size_t i = 0; i < rs.size(); ++i)
        ranges.push_back(range(rs[i], what + "[" + std::to_string(i) + "]", seconds));
    }
    return p;
  }

  const motion::Motion& motion_;
};

}  // namespace

Contacts read_contacts_string(const std::string& text, const std::string& file_name,
                              const motion::Motion& motion) {
  if (!motion.skeleton) throw Error("the motion has no skeleton", {file_name, 0, 0});
  return Reader(file_name, motion).read(text);
}

Contacts read_contacts_file(const std::string& path, const motion::Motion& motion) {
  return read_contacts_string(kg::read_input_file(path, "contact file"), path, motion);
}

}  // namespace kg::retime
