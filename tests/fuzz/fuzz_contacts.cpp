// Contact files (kg/retime/contacts.hpp) under fuzzing, against the synthesized walk. Refused: a
// placed kg::Error. Accepted: one contact frame per clip frame, patches of finite vertices, and
// every touching point a vertex of its patch, at a finite world position with a Jacobian of the
// clip's channels.
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "kg/retime/contacts.hpp"

namespace {

using kg::fuzz::require;

void check_contacts(const kg::retime::Contacts& c) {
  const kg::motion::Motion& clip = kg::fuzz::walk();
  require(c.frame_count() == clip.frame_count(), "contact frames are not the clip's");
  require(c.channel_count() == clip.skeleton->channel_count(), "contacts on another skeleton");
  for (const kg::retime::ContactPatch& p : c.patches) {
    require(!p.vertices.empty(), "patch " + p.name + " without vertices");
    for (const kg::retime::ContactVertex& v : p.vertices)
      require(v.joint >= 0 && v.joint < clip.skeleton->joint_count() && v.local.allFinite(),
              "patch " + p.name + " has a vertex outside the skeleton or not finite");
  }
  for (const kg::retime::ContactFrame& frame : c.frames) {
    for (const kg::retime::ContactPoint& point : frame.points) {
      require(point.patch >= 0 && point.patch < static_cast<int>(c.patches.size()), "a point of no patch");
      require(point.vertex >= 0 &&
                  point.vertex <
                      static_cast<int>(c.patches[static_cast<std::size_t>(point.patch)].vertices.size()),
              "a point of no vertex");
      require(point.world.allFinite(), "a touching point not finite");
      require(point.jacobian.cols() == c.channel_count() && point.jacobian.allFinite(),
              "a touching point's Jacobian not finite or not of the clip's channels");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(kg::fuzz::text(data, size));
  kg::fuzz::expect_clean("fuzz.yaml", [&] {
    check_contacts(kg::retime::read_contacts_string(text, "fuzz.yaml", kg::fuzz::walk()));
  });
  return 0;
}
