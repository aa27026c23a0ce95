// Motion formats by file extension (kg/io/motion_format.hpp) and the nodes dispatching through
// the registry's kg.MotionFormat extensions: io.import_motion and io.export_motion. A format
// registered by the test (as a plugin would, through the same Registry API) plugs in without
// any change to the dispatch.
#include <catch2/catch.hpp>

#include <filesystem>
#include <functional>
#include <istream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/yaml_io.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/io/nodes.hpp"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using kg::io::MotionFormat;
using kg::io::MotionFormats;
using kg::motion::Motion;
using kg::test::params_for;
using kg::test::run_node;

const std::string kBvh =
    "HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
    "Yrotation\n JOINT knee\n {\n  OFFSET 0 -45 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n"
    "  {\n   OFFSET 0 -45 0\n  }\n }\n End Site\n {\n  OFFSET 0 80 0\n }\n}\nMOTION\nFrames: 3\n"
    "Frame Time: 0.0333333\n0 90 0 0 0 0 10 0 0\n1 90 0 0 0 0 20 0 0\n2 90 0 0 0 0 30 0 0\n";

const std::string kBuiltinReaders =
    ".amc (ASF/AMC, skeleton .asf), .asf (ASF skeleton), .bvh (BVH), .csv (robot CSV, skeleton .urdf), .urdf "
    "(URDF)";
const std::string kBuiltinWriters = ".bvh (BVH), .csv (robot CSV), .json (robot JSON)";

// A format of the test's own, as a plugin would bring: ".TXT" files (claimed in upper case, so
// matching ignores case) holding "kg test motion" and the BVH text of the clip.
std::shared_ptr<const MotionFormat> text_format() {
  MotionFormat f;
  f.name = "Test text";
  f.extensions = {".TXT"};
  f.doc = "a BVH under a header line";
  f.write = [](std::ostream& os, const Motion& m, const kg::io::MotionWriteOptions& o) {
    os << "kg test motion\n";
    kg::io::write_bvh(os, m, {.units = o.units, .precision = o.precision});
  };
  f.read = [](const std::string& path, const std::string& skeleton, const kg::io::ImportOptions& options) {
    std::string text = kg::read_input_file(path, "test motion");
    const std::string header = "kg test motion\n";
    if (text.rfind(header, 0) != 0) throw std::invalid_argument(path + ": not a test motion");
    kg::io::BvhClip clip = kg::io::parse_bvh(std::string_view(text).substr(header.size()), path);
    kg::io::ImportedMotion in{std::move(clip.motion), {}, clip.frame_time};
    in.notes = kg::io::apply_import_options(in.motion, options, 1.0 / clip.frame_time, path, 0.0);
    in.notes.push_back("read as a test motion");
    return in;
  };
  return std::make_shared<const MotionFormat>(std::move(f));
}

kg::graph::Registry io_registry(bool with_text_format) {
  kg::graph::Registry registry = kg::test::registry_of(kg::bvh_node_types());
  for (kg::graph::NodeType& type : kg::asf_amc_node_types()) registry.add_node(std::move(type));
  for (kg::graph::Extension& format : kg::io::builtin_motion_format_extensions())
    registry.add_extension(std::move(format));
  if (with_text_format)
    registry.add_extension(
        kg::graph::Extension::make<MotionFormat>("Test text", text_format(), "a test format"));
  return registry;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("lower_extension: the one extension dispatch of io and retarget", "[io][formats]") {
  CHECK(kg::text::lower_extension("dir/Walk.BVH") == ".bvh");
  CHECK(kg::text::lower_extension("16_15.Amc") == ".amc");
  CHECK(kg::text::lower_extension("dir.v2/walk") == "");
  CHECK(kg::text::lower_extension("dir/.hidden") == "");
  CHECK(kg::text::lower_extension("a.tar.GZ") == ".gz");
}

TEST_CASE("motion formats: the built-ins claim their extensions in any case", "[io][formats]") {
  const MotionFormats formats = kg::io::builtin_motion_formats();
  CHECK(kg::io::motion_reader_for("walk.bvh", formats)->name == "BVH");
  CHECK(kg::io::motion_reader_for("dir/WALK.Bvh", formats)->name == "BVH");
  CHECK(kg::io::motion_reader_for("16_15.AMC", formats)->name == "ASF/AMC");
  CHECK(kg::io::motion_writer_for("out/x.BVH", formats)->name == "BVH");
  CHECK(kg::io::asf_amc_format()->skeleton_extension == ".asf");
  CHECK_FALSE(kg::io::asf_amc_format()->write);

  // What nothing claims is refused, naming the file and every format available.
  CHECK(message_of([&] { kg::io::motion_writer_for("x.fbx", formats); }) ==
        "x.fbx: no motion writer claims '.fbx'; writers: " + kBuiltinWriters +
            "; readers: " + kBuiltinReaders);
  CHECK(message_of([&] { kg::io::motion_writer_for("16_15.amc", formats); }) ==
        "16_15.amc: no motion writer claims '.amc'; writers: " + kBuiltinWriters +
            "; readers: " + kBuiltinReaders);
  CHECK(message_of([&] { kg::io::motion_reader_for("clip.c3d", formats); }) ==
        "clip.c3d: no motion reader claims '.c3d'; readers: " + kBuiltinReaders +
            "; writers: " + kBuiltinWriters);
  CHECK(kg::io::motion_reader_for("16.ASF", formats)->name == "ASF skeleton");
  CHECK(message_of([&] { kg::io::motion_writer_for("16.asf", formats); }) ==
        "16.asf: no motion writer claims '.asf'; writers: " + kBuiltinWriters +
            "; readers: " + kBuiltinReaders);
  CHECK(message_of([&] { kg::io::motion_reader_for("dir/clip", formats); }) ==
        "dir/clip: no motion reader claims a file without an extension; readers: " + kBuiltinReaders +
            "; writers: " + kBuiltinWriters);
  CHECK(message_of([&] { kg::io::motion_writer_for("x.bvh", {}); }) ==
        "x.bvh: no motion writer claims '.bvh'; writers: none; readers: none");
  CHECK(message_of([&] { kg::io::import_motion("clip.c3d", "", {}); }) ==
        "clip.c3d: no motion reader claims '.c3d'; readers: " + kBuiltinReaders +
            "; writers: " + kBuiltinWriters);

  // Two formats claiming one extension: neither is picked behind the user's back.
  MotionFormat other = *kg::io::bvh_format();
  other.name = "Other BVH";
  const MotionFormats both = {kg::io::bvh_format(), std::make_shared<const MotionFormat>(other)};
  CHECK_THAT(message_of([&] { kg::io::motion_writer_for("x.bvh", both); }),
             Contains("x.bvh: '.bvh' is claimed by 2 motion writers, BVH and Other BVH"));
}

TEST_CASE("io.export_motion and io.import_motion dispatch through the registry", "[io][formats][nodes]") {
  const kg::test::TempDir dir;
  const fs::path in_path = dir.write("small.bvh", kBvh);
  const kg::graph::Registry registry = io_registry(false);

  const kg::test::NodeContext in = run_node(
      registry, "io.import_motion", params_for(registry, "io.import_motion", {{"path", in_path.string()}}));
  const kg::graph::Value clip = in.outputs.at("motion");
  CHECK(clip.get<Motion>().frame_count() == 3);

  // .bvh, in any case: the same bytes as io.export_bvh, the same figures.
  const fs::path by_bvh = dir.path() / "by_bvh.bvh", by_motion = dir.path() / "sub" / "BY_MOTION.BVH";
  const auto bvh_ctx =
      run_node(registry, "io.export_bvh", params_for(registry, "io.export_bvh", {{"path", by_bvh.string()}}),
               {{"motion", clip}});
  const auto motion_ctx =
      run_node(registry, "io.export_motion",
               params_for(registry, "io.export_motion", {{"path", by_motion.string()}}), {{"motion", clip}});
  CHECK(kg::test::read_file(by_motion) == kg::test::read_file(by_bvh));
  CHECK(std::get<std::string>(motion_ctx.figures.at("units")) ==
        std::get<std::string>(bvh_ctx.figures.at("units")));
  CHECK(std::get<std::int64_t>(motion_ctx.figures.at("frames")) == 3);
  CHECK(motion_ctx.figures.size() == bvh_ctx.figures.size());

  // An unclaimed extension fails when the node is made (at load), before anything is written.
  const fs::path fbx = dir.path() / "x.fbx";
  CHECK_THROWS_WITH(registry.create_node("io.export_motion",
                                         params_for(registry, "io.export_motion", {{"path", fbx.string()}})),
                    fbx.string() + ": no motion writer claims '.fbx'; writers: " + kBuiltinWriters +
                        "; readers: " + kBuiltinReaders);
  CHECK_FALSE(fs::exists(fbx));
  CHECK_THROWS_WITH(
      registry.create_node("io.import_motion", params_for(registry, "io.import_motion",
                                                          {{"path", (dir.path() / "x.c3d").string()}})),
      Contains("x.c3d: no motion reader claims '.c3d'; readers: " + kBuiltinReaders));
  // Made without a registry, such a node type says how to run it.
  CHECK_THROWS_WITH(run_node(kg::test::node_type(registry, "io.export_motion"),
                             params_for(registry, "io.export_motion", {{"path", by_bvh.string()}})),
                    Contains("run_node(registry"));
}

TEST_CASE("a graph writing to an extension no writer claims is refused at load", "[io][formats][graph]") {
  const kg::graph::Registry registry = io_registry(false);
  const std::string graph =
      "version: 1\n"
      "nodes:\n"
      "  source: {type: io.import_motion, params: {path: in.bvh}}\n"
      "  write:\n"
      "    type: io.export_motion\n"
      "    params: {path: out/x.fbx}\n"
      "connections:\n"
      "  - {from: source.motion, to: write.motion}\n";
  const std::string message =
      message_of([&] { kg::graph::load_graph_from_string(graph, "convert.yaml", registry); });
  CHECK_THAT(message,
             Contains("convert.yaml:4:3: node 'write' (io.export_motion): out/x.fbx: no motion writer "
                      "claims '.fbx'; writers: " +
                      kBuiltinWriters + "; readers: " + kBuiltinReaders));
  std::string reading = graph;
  reading.replace(reading.find("in.bvh"), 6, "in.C3D");
  reading.replace(reading.find("out/x.fbx"), 9, "out/x.bvh");
  CHECK_THAT(
      message_of([&] { kg::graph::load_graph_from_string(reading, "convert.yaml", registry); }),
      Contains("convert.yaml:3:3: node 'source' (io.import_motion): in.C3D: no motion reader claims '.c3d'"));
}

TEST_CASE("a format registered like a plugin's plugs into both nodes", "[io][formats][nodes]") {
  const kg::test::TempDir dir;
  const fs::path in_path = dir.write("small.bvh", kBvh);
  const kg::graph::Registry registry = io_registry(true);
  CHECK(registry.names<MotionFormat>() == std::vector<std::string>{"ASF skeleton", "ASF/AMC", "BVH",
                                                                   "Test text", "URDF", "robot CSV",
                                                                   "robot JSON"});

  const auto in = run_node(registry, "io.import_motion",
                           params_for(registry, "io.import_motion", {{"path", in_path.string()}}));
  const fs::path text_path = dir.path() / "clip.txt";
  run_node(registry, "io.export_motion",
           params_for(registry, "io.export_motion", {{"path", text_path.string()}}),
           {{"motion", in.outputs.at("motion")}});
  const std::string text = kg::test::read_file(text_path);
  CHECK(text.rfind("kg test motion\nHIERARCHY\n", 0) == 0);

  const fs::path upper = dir.path() / "CLIP.TXT";
  fs::copy_file(text_path, upper);
  const auto back = run_node(registry, "io.import_motion",
                             params_for(registry, "io.import_motion", {{"path", upper.string()}}));
  CHECK(back.logged("read as a test motion"));
  CHECK(back.outputs.at("motion").get<Motion>().frame_count() == 3);

  // The lists in messages now name it too.
  CHECK_THROWS_WITH(
      registry.create_node("io.export_motion",
                           params_for(registry, "io.export_motion", {{"path", std::string("x.fbx")}})),
      "x.fbx: no motion writer claims '.fbx'; writers: .bvh (BVH), .csv (robot CSV), .json (robot JSON), "
      ".txt "
      "(Test text); readers: .amc (ASF/AMC, skeleton .asf), .asf (ASF skeleton), .bvh (BVH), .csv (robot "
      "CSV, skeleton .urdf), "
      ".txt (Test text), .urdf (URDF)");
}
