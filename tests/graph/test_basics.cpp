// The small pieces of kg::graph: errors and "did you mean", values and their owners, params,
// the registry, the JSON writer and atomic writes.
#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <fstream>
#include <sstream>
#include <thread>

#include "../support/temp_dir.hpp"
#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/json.hpp"
#include "kg/graph/registry.hpp"
#include "kg/graph/value.hpp"
#include "test_nodes.hpp"

using namespace kg;
using namespace kg::graph;
using kg::test::read_file;
using kg::test::TempDir;
using kg_test::TestAnswer;
using kg_test::TestQuestion;

namespace {

// Counts live instances, so tests can see when a value's storage is released.
struct Tracked {
  static inline std::atomic<int> alive{0};
  int payload = 0;
  explicit Tracked(int p) : payload(p) { ++alive; }
  Tracked(const Tracked& o) : payload(o.payload) { ++alive; }
  Tracked(Tracked&& o) noexcept : payload(o.payload) { ++alive; }
  ~Tracked() { --alive; }
};

std::vector<std::string> temp_files_in(const std::filesystem::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp.") != std::string::npos) out.push_back(e.path().string());
  return out;
}

}  // namespace

KG_DECLARE_TYPE(Tracked, "test.Tracked")

TEST_CASE("SourceLocation and Error format file:line:column") {
  CHECK(SourceLocation{"g.yaml", 3, 7}.to_string() == "g.yaml:3:7");
  CHECK(SourceLocation{"g.yaml", 3, 0}.to_string() == "g.yaml:3");
  CHECK(SourceLocation{"g.yaml", 0, 0}.to_string() == "g.yaml");
  CHECK(SourceLocation{}.to_string().empty());
  Error e("bad thing", {"g.yaml", 3, 7});
  CHECK(std::string(e.what()) == "g.yaml:3:7: bad thing");
  CHECK(e.message() == "bad thing");
  CHECK(e.where().line == 3);
  CHECK(std::string(Error("no place").what()) == "no place");
}

TEST_CASE("nearest_name suggests close names and nothing for far ones") {
  const std::vector<std::string> keys = {"type", "params", "doc"};
  CHECK(nearest_name("parms", keys) == "params");
  CHECK(nearest_name("parmas", keys) == "params");  // transposition counts as one edit
  CHECK(nearest_name("Type", keys) == "type");
  CHECK(nearest_name("dox", keys) == "doc");
  CHECK(nearest_name("xyzzy", keys).empty());
  CHECK(nearest_name("", keys).empty());
  CHECK(nearest_name("a", {}).empty());
  const std::vector<std::string> types = {"io.export_bvh", "io.import_bvh", "motion.resample",
                                          "motion.synthesize"};
  CHECK(nearest_name("io.import_bhv", types) == "io.import_bvh");
  CHECK(nearest_name("import_bvh", types) == "io.import_bvh");
  CHECK(nearest_name("motion.resampel", types) == "motion.resample");
  CHECK(nearest_name("filter.lowpass", types).empty());
}

TEST_CASE("Value holds a named type and refuses another") {
  Value v = Value::make(2.5);
  CHECK(v.type_name() == "kg.Scalar");
  CHECK(v.holds<double>());
  CHECK_FALSE(v.holds<std::int64_t>());
  CHECK(v.get<double>() == 2.5);
  try {
    (void)v.get<std::string>();
    FAIL("no throw");
  } catch (const Error& e) {
    CHECK_THAT(e.what(), Catch::Contains("kg.String") && Catch::Contains("kg.Scalar"));
  }
  Value empty;
  CHECK(empty.empty());
  CHECK_THROWS_WITH(empty.get<double>(), Catch::Contains("got none"));
  auto shared = std::make_shared<const std::string>("abc");
  Value s = Value::share(shared);
  CHECK(&s.get<std::string>() == shared.get());
  CHECK(s.get_shared<std::string>() == shared);
}

TEST_CASE("kept_alive_by keeps the owner until the value is gone, and releases data first") {
  Tracked::alive = 0;
  int alive_when_owner_died = -1;
  {
    auto owner = std::shared_ptr<int>(new int(1), [&](int* p) {
      alive_when_owner_died = Tracked::alive;
      delete p;
    });
    std::weak_ptr<int> watch = owner;
    Value kept;
    {
      Value v = Value::make(Tracked(7));
      kept = v.kept_alive_by(owner);
    }
    owner.reset();
    CHECK_FALSE(watch.expired());
    CHECK(kept.type_name() == "test.Tracked");
    CHECK(kept.get<Tracked>().payload == 7);
    CHECK(Tracked::alive == 1);
    Value copy = kept;
    kept = Value();
    CHECK_FALSE(watch.expired());
    copy = Value();
    CHECK(watch.expired());
  }
  CHECK(Tracked::alive == 0);
  CHECK(alive_when_owner_died == 0);  // the data was destroyed before the owner
  // No owner: the same value back.
  Value v = Value::make(1.0);
  CHECK(&v.kept_alive_by({}).get<double>() == &v.get<double>());
}

TEST_CASE("ParamType and ParamValue print as documented") {
  CHECK(std::string(to_string(ParamType::InputPath)) == "input_path");
  CHECK(std::string(to_string(ParamType::FloatList)) == "float_list");
  CHECK(std::string(to_string(ParamType::Enum)) == "enum");
  CHECK(to_string(ParamValue{true}) == "true");
  CHECK(to_string(ParamValue{std::int64_t{3}}) == "3");
  CHECK(to_string(ParamValue{0.5}) == "0.5");
  CHECK(to_string(ParamValue{2.0}) == "2.0");
  CHECK(to_string(ParamValue{std::string("a \"b\"")}) == "\"a \\\"b\\\"\"");
  CHECK(to_string(ParamValue{std::vector<double>{1, -9.81, 0.5}}) == "[1.0, -9.81, 0.5]");
  Params p({{"x", 1.5}});
  CHECK(p.has("x"));
  CHECK(p.get<double>("x") == 1.5);
  CHECK_THROWS_AS(p.get<std::int64_t>("x"), std::bad_variant_access);
  CHECK_THROWS_WITH(p.get<double>("y"), Catch::Contains("'y'"));
}

TEST_CASE("Registry refuses a duplicate type naming both origins") {
  Registry r;
  NodeType t{{"demo.node", 1, "", {}, {}, {}},
             [](const Params&) { return kg_test::make_fn_node([](RunContext&) {}); }};
  r.add_node(t, {}, "built-in");
  try {
    r.add_node(t, {}, "/plugins/other.so");
    FAIL("no throw");
  } catch (const Error& e) {
    CHECK_THAT(e.what(), Catch::Contains("demo.node") && Catch::Contains("built-in") &&
                             Catch::Contains("/plugins/other.so"));
  }
  CHECK(r.node_type_names() == std::vector<std::string>{"demo.node"});
  CHECK(r.node_origin("demo.node") == "built-in");
  CHECK(r.find_node("demo.none") == nullptr);
}

TEST_CASE("Registry checks specs and normalises defaults") {
  Registry r;
  auto make = [](const Params&) { return kg_test::make_fn_node([](RunContext&) {}); };
  NodeSpec s{"demo.defaults", 1, "", {}, {}, {}};
  s.params.push_back({"f", ParamType::Float, std::int64_t{2}, ""});  // 2 -> 2.0
  s.params.push_back({"l", ParamType::FloatList, 1.5, ""});          // 1.5 -> [1.5]
  r.add_node({s, make});
  const NodeSpec& got = r.find_node("demo.defaults")->spec;
  CHECK(std::get<double>(got.params[0].default_value) == 2.0);
  CHECK(std::get<std::vector<double>>(got.params[1].default_value) == std::vector<double>{1.5});

  NodeSpec bad{"demo.bad", 1, "", {}, {}, {}};
  bad.params.push_back({"n", ParamType::Int, std::string("three"), ""});
  CHECK_THROWS_WITH(r.add_node({bad, make}), Catch::Contains("demo.bad") && Catch::Contains("'n'"));
  NodeSpec range{"demo.range", 1, "", {}, {}, {}};
  ParamSpec p{"x", ParamType::Float, 5.0, ""};
  p.max = 1.0;
  range.params.push_back(p);
  CHECK_THROWS_WITH(r.add_node({range, make}), Catch::Contains("out of its range"));
  NodeSpec enum_spec{"demo.enum", 1, "", {}, {}, {}};
  ParamSpec e{"m", ParamType::Enum, std::string("z"), ""};
  e.choices = {"a", "b"};
  enum_spec.params.push_back(e);
  CHECK_THROWS_WITH(r.add_node({enum_spec, make}), Catch::Contains("not one of its choices"));
  NodeSpec ports{"demo.ports", 1, "", {kg_test::scalar_port("a"), kg_test::scalar_port("a")}, {}, {}};
  CHECK_THROWS_WITH(r.add_node({ports, make}), Catch::Contains("two input ports named 'a'"));
  CHECK_THROWS_WITH(r.add_node({NodeSpec{"demo.nofactory", 1, "", {}, {}, {}}, nullptr}),
                    Catch::Contains("no factory"));
  CHECK_THROWS_WITH(r.add_node({NodeSpec{"bad name", 1, "", {}, {}, {}}, make}), Catch::Contains("blanks"));
  CHECK(r.node_type_names() == std::vector<std::string>{"demo.defaults"});  // refused types left nothing
}

TEST_CASE("Registry::create_node suggests the nearest type and keeps a plugin's owner alive") {
  Registry r;
  auto owner = std::make_shared<int>(5);
  std::weak_ptr<int> watch = owner;
  NodeType t{{"demo.owned", 1, "", {}, {}, {}},
             [](const Params&) { return kg_test::make_fn_node([](RunContext&) {}); }};
  r.add_node(t, owner, "/plugins/demo.so");
  owner.reset();
  CHECK_THROWS_WITH(r.create_node("demo.ownd", {}), Catch::Contains("unknown node type 'demo.ownd'") &&
                                                        Catch::Contains("did you mean 'demo.owned'"));
  NodePtr node = r.create_node("demo.owned", {});
  CHECK(r.node_owner("demo.owned") != nullptr);
  CHECK(r.node_owner("demo.none") == nullptr);
  r = Registry();  // the registry forgets the plugin; the node still holds it
  CHECK_FALSE(watch.expired());
  node.reset();
  CHECK(watch.expired());
}

TEST_CASE("Registry extensions: typed, guarded by interface, owners kept") {
  Registry r;
  auto owner = std::make_shared<int>(1);
  std::weak_ptr<int> watch = owner;
  auto answer = std::make_shared<const TestAnswer>(TestAnswer{42});
  r.add_extension(Extension::make<TestAnswer>("ladder.rung", answer, "a rung"), owner, "/p/ladder.so");
  owner.reset();
  CHECK_THROWS_WITH(
      r.add_extension(Extension::make<TestAnswer>("ladder.rung", answer), {}, "built-in"),
      Catch::Contains("extension kg.TestAnswer 'ladder.rung' from built-in is already registered by "
                      "/p/ladder.so"));
  CHECK_THROWS_WITH(r.add_extension(Extension::make<TestAnswer>("empty", nullptr)),
                    Catch::Contains("extension kg.TestAnswer 'empty' from built-in has no factory"));
  CHECK_THROWS_WITH(r.add_extension(Extension::make<TestAnswer>("", answer)),
                    Catch::Contains("needs an interface and a name"));
  CHECK_THROWS_WITH(r.add_extension(Extension{}), Catch::Contains("needs an interface and a name"));
  // Same name, other interface: a separate entry.
  r.add_extension(
      Extension::make<TestQuestion>("ladder.rung", std::make_shared<const TestQuestion>(TestQuestion{"?"})));
  CHECK(r.find<TestAnswer>("nope") == nullptr);
  CHECK(r.find_extension("kg.Nope", "ladder.rung") == nullptr);
  std::shared_ptr<const TestAnswer> got = r.find<TestAnswer>("ladder.rung");
  REQUIRE(got);
  CHECK(got->value == 42);
  CHECK(r.find<TestQuestion>("ladder.rung")->text == "?");
  CHECK(r.names<TestAnswer>() == std::vector<std::string>{"ladder.rung"});
  CHECK(r.names<TestQuestion>() == std::vector<std::string>{"ladder.rung"});
  CHECK(r.extension_names("kg.TestAnswer") == r.names<TestAnswer>());
  r = Registry();
  CHECK_FALSE(watch.expired());  // the pointer handed out keeps the owner
  got.reset();
  CHECK(watch.expired());
}

TEST_CASE("Extension: typed access and kept_alive_by") {
  const Extension e =
      Extension::make<TestAnswer>("a", std::make_shared<const TestAnswer>(TestAnswer{7}), "doc");
  CHECK(e.interface() == "kg.TestAnswer");
  CHECK(e.name() == "a");
  CHECK(e.doc() == "doc");
  CHECK_FALSE(e.empty());
  CHECK(e.get<TestAnswer>()->value == 7);
  CHECK(e.get<TestQuestion>() == nullptr);
  CHECK(Extension{}.get<TestAnswer>() == nullptr);

  auto owner = std::make_shared<int>(1);
  std::weak_ptr<int> watch = owner;
  Extension kept = e.kept_alive_by(std::move(owner));
  CHECK(kept.get<TestAnswer>().get() == e.get<TestAnswer>().get());
  CHECK_FALSE(watch.expired());
  kept = Extension{};
  CHECK(watch.expired());
}

TEST_CASE("Registry: a node type made from the registry sees its extensions") {
  Registry r;
  r.add_extension(Extension::make<TestAnswer>("answer", std::make_shared<const TestAnswer>(TestAnswer{42})));
  NodeSpec s{"test.made_with", 1, "", {}, {{"out", "kg.Scalar", true, ""}}, {}};
  NodeType type{s, {}};
  type.create_with_registry = [](const Params&, const Registry& registry) {
    std::shared_ptr<const TestAnswer> answer = registry.find<TestAnswer>("answer");
    if (!answer) throw std::runtime_error("no answer");
    return kg_test::make_fn_node([answer](RunContext& ctx) { ctx.output("out", answer->value); });
  };
  r.add_node(type);
  CHECK(r.create_node("test.made_with", {}) != nullptr);
  Registry without;
  without.add_node(type);
  CHECK_THROWS_WITH(without.create_node("test.made_with", {}), "no answer");
  NodeType none{NodeSpec{"test.none", 1, "", {}, {}, {}}, {}};
  CHECK_THROWS_WITH(r.add_node(none), Catch::Contains("has no factory"));
}

TEST_CASE("JsonWriter writes nested structures and escapes strings") {
  std::ostringstream os;
  JsonWriter w(os, 0);
  w.begin_object();
  w.key("s");
  w.value("a\"b\\c\nd\te\x01 \xc3\xa9");
  w.key("n");
  w.value(3);
  w.key("x");
  w.value(0.1);
  w.key("big");
  w.value(std::int64_t{-9007199254740993});
  w.key("inf");
  w.value(std::numeric_limits<double>::infinity());
  w.key("nan");
  w.value(std::nan(""));
  w.key("ok");
  w.value(false);
  w.key("none");
  w.null();
  w.key("list");
  w.begin_array();
  w.value(1.5);
  w.value(2.0);
  w.value(-1e22);
  w.begin_object();
  w.end_object();
  w.begin_array();
  w.end_array();
  w.end_array();
  w.end_object();
  CHECK(
      os.str() ==
      R"({"s":"a\"b\\c\nd\te\u0001 )"
      "\xc3\xa9"
      R"(","n":3,"x":0.1,"big":-9007199254740993,"inf":null,"nan":null,"ok":false,"none":null,"list":[1.5,2.0,-1e+22,{},[]]})");
  // nlohmann escapes what JSON requires (below 0x20) and passes DEL through; bytes that are not
  // UTF-8 become U+FFFD, so the text is always valid JSON.
  CHECK(json_quote("\x7f") == "\"\x7f\"");
  CHECK(json_quote("a\xff") == "\"a\xef\xbf\xbd\"");
}

TEST_CASE("JsonWriter refuses a document it cannot write") {
  std::ostringstream os;
  JsonWriter w(os, 0);
  w.begin_object();
  CHECK_THROWS_AS(w.value(1), std::logic_error);  // no key
  w.field("a", 1);
  CHECK_THROWS_AS(w.field("a", 2), std::logic_error);
  CHECK_THROWS_AS(w.end_array(), std::logic_error);
  w.end_object();
  CHECK(os.str() == R"({"a":1})");
  CHECK_THROWS_AS(w.end_object(), std::logic_error);
  w.value(2.0);  // a lone value at the top goes out at once
  CHECK(os.str() == R"({"a":1}2.0)");
}

TEST_CASE("JsonWriter pretty-prints with an indent") {
  std::ostringstream os;
  JsonWriter w(os, 2);
  w.begin_object();
  w.key("a");
  w.begin_array();
  w.value(1);
  w.value(2);
  w.end_array();
  w.key("b");
  w.begin_object();
  w.end_object();
  w.end_object();
  CHECK(os.str() == "{\n  \"a\": [\n    1,\n    2\n  ],\n  \"b\": {}\n}\n");
}

TEST_CASE("write_file_atomically writes, replaces, and creates folders") {
  TempDir dir;
  const auto target = dir / "sub" / "deeper" / "out.txt";
  write_file_atomically(target, [](std::ostream& os) { os << "first"; });
  CHECK(read_file(target) == "first");
  write_file_atomically(target, [](std::ostream& os) { os << "second, longer"; });
  CHECK(read_file(target) == "second, longer");
  CHECK(temp_files_in(dir.path()).empty());
}

TEST_CASE("write_file_atomically leaves the target untouched when the writer throws") {
  TempDir dir;
  const auto target = dir / "out.txt";
  dir.write("out.txt", "original");
  try {
    write_file_atomically(target, [](std::ostream& os) {
      os << "half written";
      throw std::runtime_error("writer broke");
    });
    FAIL("no throw");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains(target.string()) && Catch::Contains("writer broke"));
    // The writer's own exception is nested inside.
    bool nested_found = false;
    try {
      std::rethrow_if_nested(e);
    } catch (const std::runtime_error& inner) {
      nested_found = std::string(inner.what()) == "writer broke";
    }
    CHECK(nested_found);
  }
  CHECK(read_file(target) == "original");
  CHECK(temp_files_in(dir.path()).empty());

  // A stream put into a failed state counts as a failure too.
  CHECK_THROWS_WITH(write_file_atomically(target, [](std::ostream& os) { os.setstate(std::ios::badbit); }),
                    Catch::Contains(target.string()));
  CHECK(read_file(target) == "original");
  CHECK(temp_files_in(dir.path()).empty());
}

TEST_CASE("write_file_atomically refuses a directory target and an unwritable place") {
  TempDir dir;
  CHECK_THROWS_WITH(write_file_atomically(dir.path(), [](std::ostream& os) { os << "x"; }),
                    Catch::Contains(dir.path().string()));
  dir.write("file", "x");
  // A parent that is a file cannot be created as a directory.
  CHECK_THROWS_WITH(write_file_atomically(dir / "file" / "out.txt", [](std::ostream& os) { os << "x"; }),
                    Catch::Contains("out.txt"));
  CHECK(temp_files_in(dir.path()).empty());
}

TEST_CASE("read_input_file reads whole files and protects them from every later write") {
  TempDir dir;
  const auto clip = dir.write("clip.txt", "frames 3\n");
  CHECK(read_input_file(clip, "clip file") == "frames 3\n");
  CHECK(is_input_file(clip));
  CHECK(is_input_file(dir.path() / "." / "clip.txt"));  // another spelling of the same file
  CHECK_THROWS_WITH(write_file_atomically(clip, [](std::ostream& os) { os << "oops"; }),
                    Catch::Contains("clip.txt") && Catch::Contains("never overwritten"));
  CHECK(read_file(clip) == "frames 3\n");

  std::error_code ec;
  std::filesystem::create_hard_link(clip, dir.path() / "link.txt", ec);
  if (!ec)
    CHECK_THROWS(write_file_atomically(dir.path() / "link.txt", [](std::ostream& os) { os << "oops"; }));
  CHECK_NOTHROW(write_file_atomically(dir.path() / "other.txt", [](std::ostream& os) { os << "fine"; }));

  CHECK_THROWS_WITH(read_input_file(dir.path() / "absent.txt", "clip file"),
                    Catch::Contains("absent.txt: no such clip file"));
  CHECK_THROWS_WITH(read_input_file(dir.path(), "clip file"),
                    Catch::Contains("clip file expected, got a directory"));
}

TEST_CASE("map_input_file: a regular file mapped, a pipe read, the same text either way") {
  TempDir dir;
  const std::string big(1 << 20, 'x');
  const auto file = dir.write("big.bvh", "\xef\xbb\xbf" + big);
  InputText mapped = map_input_file(file, "BVH file");
  CHECK(mapped.text() == big);  // the UTF-8 byte-order mark dropped
  CHECK(is_input_file(file));
  InputText moved = std::move(mapped);
  CHECK(moved.text() == big);
  CHECK(mapped.text().empty());

  const auto empty = dir.write("empty.bvh", "");
  CHECK(map_input_file(empty, "BVH file").text().empty());

  // A FIFO is no regular file: read through a stream, the BOM dropped from the string it owns.
  const auto fifo = dir.path() / "clip.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  std::thread writer([&] { std::ofstream(fifo) << "\xef\xbb\xbfHIERARCHY"; });
  InputText piped = map_input_file(fifo, "BVH file");
  writer.join();
  InputText kept;
  kept = std::move(piped);  // the view follows the string it points into
  CHECK(kept.text() == "HIERARCHY");
  CHECK(read_input_file(file, "BVH file") == big);

  CHECK_THROWS_WITH(map_input_file(dir.write("utf16.bvh", std::string("\xff\xfeH\0", 4)), "BVH file"),
                    Catch::Contains("utf16.bvh:1:1: BVH file is UTF-16 (little-endian) text"));
}
