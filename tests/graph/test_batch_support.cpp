// The library pieces behind `kinegraph batch`: SHA-256 against FIPS 180-4 and independently
// computed digests, input patterns with `**`, JSON-lines manifests (round trip, torn lines,
// supersession), the list of files written and the removal of pending temporaries, and reading a
// graph's declared variables without resolving them.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <regex>
#include <string>
#include <variant>
#include <vector>

#include "../support/temp_dir.hpp"
#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/graph/file_patterns.hpp"
#include "kg/graph/manifest.hpp"
#include "kg/graph/sha256.hpp"
#include "kg/graph/yaml_io.hpp"

using namespace kg;
using namespace kg::graph;
using kg::test::read_file;
using kg::test::TempDir;

namespace fs = std::filesystem;

namespace {

constexpr const char* kEmptyDigest = "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855";

// Bytes (7 i + 3) mod 256: every byte value, no text structure.
std::string pattern_bytes(std::size_t n) {
  std::string s(n, '\0');
  for (std::size_t i = 0; i < n; ++i) s[i] = static_cast<char>((7 * i + 3) % 256);
  return s;
}

// ---- file patterns ------------------------------------------------------------------------------

// root/top.bvh, top.amc, .hidden.bvh, a/{x.bvh, y.bvh, y.txt, z1.bvh}, b/w.bvh, c/d/deep.bvh,
// c/d/e/deeper.bvh, .git/ignored.bvh, and a folder named folder.bvh holding inner.bvh.
struct PatternTree {
  TempDir dir;
  PatternTree() {
    for (const char* name :
         {"top.bvh", "top.amc", ".hidden.bvh", "a/x.bvh", "a/y.bvh", "a/y.txt", "a/z1.bvh", "b/w.bvh",
          "c/d/deep.bvh", "c/d/e/deeper.bvh", ".git/ignored.bvh", "folder.bvh/inner.bvh"})
      dir.write(name, name);
  }
  std::string operator()(const std::string& relative) const { return (dir.path() / relative).string(); }
  std::vector<fs::path> files(const std::vector<std::string>& relatives) const {
    std::vector<fs::path> out;
    for (const std::string& r : relatives) out.push_back((dir.path() / r).lexically_normal());
    return out;
  }
};

std::string invalid_argument_of(const std::vector<std::string>& patterns) {
  try {
    expand_file_patterns(patterns);
  } catch (const std::invalid_argument& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("NOT std::invalid_argument: ") + e.what();
  }
  return "NO ERROR";
}

// Runs a scope in another working directory, restoring the previous one after.
struct InFolder {
  fs::path saved = fs::current_path();
  explicit InFolder(const fs::path& folder) { fs::current_path(folder); }
  ~InFolder() {
    std::error_code ec;
    fs::current_path(saved, ec);
  }
};

// ---- manifests ----------------------------------------------------------------------------------

ManifestRecord full_record() {
  ManifestRecord r;
  r.input = "/data/Gänge/walk 01.bvh";
  r.stem = "walk 01";
  r.item = "Gänge/walk 01";
  r.status = "failed";
  r.message = "solve failed:\n  line \"two\"\twith a tab, a backslash \\ and a CR\r";
  r.wall_seconds = 1.25;
  r.graph_seconds = 0.1;
  r.log = "logs/walk 01.log";
  r.outputs = {{"walk 01/walk 01.bvh", std::string(64, 'a'), 81234},
               {"/elsewhere/empty.txt", kEmptyDigest, 0},
               {"big.bin", std::string(64, 'f'), 123456789012ULL}};
  r.reads = {{"/data/cmu/walk 01.bvh", std::string(64, 'b'), 512000}, {"/data/16.asf", kEmptyDigest, 0}};
  r.figures = {{"solve.iterations", std::int64_t{12}},
               {"solve.converged", true},
               {"check.failed", false},
               {"import.offset", std::int64_t{-42}},
               {"big.count", std::int64_t{9007199254740993}},  // not a double: 2^53 + 1
               {"solve.residual", 0.1},
               {"solve.tiny", -1.5e-7},
               {"solve.huge", 6.02e23},
               {"a.note", std::string("say \"hi\" \\ to C:\\data\nnext line — Grüße, 歩行")},
               {"a.numeric_text", std::string("12")},
               {"a.boolean_text", std::string("true")},
               {"a.empty", std::string()},
               {"z.last: {odd} key, #1", std::int64_t{0}}};
  r.input_sha256 = std::string(64, '1');
  r.graph_sha256 = std::string(64, '2');
  r.settings_sha256 = std::string(64, '3');
  r.finished_at = "2026-11-22T07:00:00Z";
  r.host = "node1";
  r.shard = "0/4";
  return r;
}

void check_same(const std::vector<ManifestFile>& got, const std::vector<ManifestFile>& want) {
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    CHECK(got[i].path == want[i].path);
    CHECK(got[i].sha256 == want[i].sha256);
    CHECK(got[i].bytes == want[i].bytes);
  }
}

void check_same(const ManifestRecord& got, const ManifestRecord& want) {
  CHECK(got.input == want.input);
  CHECK(got.stem == want.stem);
  CHECK(got.item == want.item);
  CHECK(got.status == want.status);
  CHECK(got.message == want.message);
  CHECK(got.wall_seconds == want.wall_seconds);
  CHECK(got.graph_seconds == want.graph_seconds);
  CHECK(got.log == want.log);
  check_same(got.outputs, want.outputs);
  check_same(got.reads, want.reads);
  REQUIRE(got.figures.size() == want.figures.size());
  for (std::size_t i = 0; i < got.figures.size(); ++i) {
    INFO("figure " << want.figures[i].first);
    CHECK(got.figures[i].first == want.figures[i].first);
    CHECK(got.figures[i].second.index() == want.figures[i].second.index());
    CHECK(got.figures[i].second == want.figures[i].second);
  }
  CHECK(got.input_sha256 == want.input_sha256);
  CHECK(got.graph_sha256 == want.graph_sha256);
  CHECK(got.settings_sha256 == want.settings_sha256);
  CHECK(got.finished_at == want.finished_at);
  CHECK(got.host == want.host);
  CHECK(got.shard == want.shard);
}

ManifestRecord record(const std::string& input, const std::string& finished_at, const std::string& host) {
  ManifestRecord r;
  r.input = input;
  r.stem = fs::path(input).stem().string();
  r.status = "ok";
  r.finished_at = finished_at;
  r.host = host;
  return r;
}

// ---- atomic files -------------------------------------------------------------------------------

std::vector<std::string> temporaries_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp.") != std::string::npos)
      out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<fs::path> written_since(std::size_t before) {
  const std::vector<fs::path> all = written_files();
  REQUIRE(all.size() >= before);
  return {all.begin() + static_cast<std::ptrdiff_t>(before), all.end()};
}

std::string graph_error_of(const fs::path& file) {
  try {
    read_graph_variables(file);
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("NOT a kg::Error: ") + e.what();
  }
  return "NO ERROR";
}

}  // namespace

// ---- SHA-256 ------------------------------------------------------------------------------------

TEST_CASE("sha256_hex matches the FIPS 180-4 examples") {
  CHECK(sha256_hex("") == kEmptyDigest);
  CHECK(sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  CHECK(
      sha256_hex(
          "abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnopqklmnopqrlmnopqrsmn"
          "opqrstnopqrstu") == "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
}

TEST_CASE("Sha256 gives the same digest however the bytes are split into update calls") {
  // One million 'a' (FIPS 180-4), in chunks that start and end everywhere inside a block.
  const std::string million(1000000, 'a');
  const std::size_t chunks[] = {1, 63, 64, 65, 1000};
  Sha256 s;
  std::size_t done = 0;
  for (std::size_t i = 0; done < million.size(); ++i) {
    const std::size_t n = std::min(chunks[i % 5], million.size() - done);
    s.update(million.data() + done, n);
    done += n;
  }
  CHECK(s.hex() == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  CHECK(sha256_hex(million) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");

  // Lengths around the padding boundaries (55/56 bytes: length fits in the last block or not),
  // digests from Python's hashlib; each split at every point.
  const std::pair<std::size_t, const char*> cases[] = {
      {55, "e7313d333c272e639f790978283f9eb392e843d0f29b7016828bb1daa4aac70b"},
      {56, "4324d65f3c103567f5589c710bc08f8523f929a9272e3af36fc968e52abc6c27"},
      {57, "35df609437dcfea3279283ab79fd554e2bf78f8f7ae2de532d8ee300b09e8f73"},
      {63, "81c80242132f230c3bd41b3e63bbcff16107339549214a99614ff26664625055"},
      {64, "39e3d7b6b5d075d37d053ad89b24b41bef4f3c29760c84447cab3f3be1882241"},
      {65, "aacca6ff74fdbb296d165a45cecfa04e5127bc008770fbbdd48006f2d2fae95e"},
      {119, "9ce7368e4daf32341631b492e80359dc9f594b48453cd0dd5bf0b19279cc177e"},
      {120, "7836b787757e95e58b3ca5aec90b1b004e8deba1e50e9675af9cabf1a13a04b5"},
      {128, "d2742f1f4ac6bb7ca2b239ee18402ba8b3f9f8e652d2a72973c2b9ba11c08cf6"}};
  for (const auto& [length, digest] : cases) {
    INFO("length " << length);
    const std::string bytes = pattern_bytes(length);
    CHECK(sha256_hex(bytes) == digest);
    for (std::size_t split = 0; split <= length; ++split) {
      Sha256 h;
      h.update(std::string_view(bytes).substr(0, split));
      h.update(std::string_view(bytes).substr(split));
      CHECK(h.hex() == digest);
    }
    Sha256 bytewise;
    for (char c : bytes) bytewise.update(&c, 1);
    CHECK(bytewise.hex() == digest);
  }
}

TEST_CASE("a copied Sha256 goes on from the bytes hashed so far, a moved one is the same hash") {
  Sha256 ab;
  ab.update("ab");
  Sha256 abc = ab;  // the copy's state is its own
  abc.update("c");
  ab.update("d");
  CHECK(abc.hex() == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(ab.hex() == sha256_hex("abd"));
  Sha256 a;
  a.update("a");
  Sha256 moved = std::move(a);
  moved.update("bc");
  CHECK(moved.hex() == sha256_hex("abc"));
  Sha256 assigned;
  assigned.update("unrelated");
  Sha256 source;
  source.update("abc");
  assigned = source;
  CHECK(assigned.hex() == sha256_hex("abc"));
}

TEST_CASE("sha256_file hashes a file's bytes and names a file it cannot read") {
  TempDir dir;
  // Over 64 KiB, not a multiple of the read block, with NUL and 0xff bytes.
  const std::string content = pattern_bytes(3 * 65536 + 1234);
  const fs::path big = dir.write("big.bin", content);
  REQUIRE(fs::file_size(big) == content.size());
  CHECK(sha256_file(big) == sha256_hex(content));
  CHECK(sha256_file(big) != sha256_hex(content.substr(0, content.size() - 1)));
  CHECK(sha256_file(dir.write("empty", "")) == kEmptyDigest);
  CHECK(sha256_file(dir.write("abc.txt", "abc")) ==
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");

  const fs::path missing = dir / "missing.bin";
  CHECK_THROWS_AS(sha256_file(missing), std::runtime_error);
  CHECK_THROWS_WITH(sha256_file(missing), Catch::Contains("'" + missing.string() + "'"));
  // A folder opens but cannot be read.
  CHECK_THROWS_WITH(sha256_file(dir.path()), Catch::Contains("'" + dir.path().string() + "'"));
}

// ---- file patterns ------------------------------------------------------------------------------

TEST_CASE("expand_file_patterns: *, ? and [...] match within one folder") {
  const PatternTree t;
  CHECK(expand_file_patterns({t("a/*.bvh")}) == t.files({"a/x.bvh", "a/y.bvh", "a/z1.bvh"}));
  CHECK(expand_file_patterns({t("*.bvh")}) == t.files({"top.bvh"}));  // not .hidden.bvh, not folder.bvh/
  CHECK(expand_file_patterns({t("a/?.bvh")}) == t.files({"a/x.bvh", "a/y.bvh"}));
  CHECK(expand_file_patterns({t("a/y.???")}) == t.files({"a/y.bvh", "a/y.txt"}));
  CHECK(expand_file_patterns({t("[ab]/*.bvh")}) == t.files({"a/x.bvh", "a/y.bvh", "a/z1.bvh", "b/w.bvh"}));
  CHECK(expand_file_patterns({t("a/[xz]*")}) == t.files({"a/x.bvh", "a/z1.bvh"}));
  CHECK(expand_file_patterns({t("a/[!x]*.bvh")}) == t.files({"a/y.bvh", "a/z1.bvh"}));
  CHECK(expand_file_patterns({t("*/w.bvh")}) == t.files({"b/w.bvh"}));
  // Folders are never returned, even when their names match.
  CHECK(expand_file_patterns({t("*")}) == t.files({"top.amc", "top.bvh"}));
}

TEST_CASE("expand_file_patterns: ** matches any number of folders, none included") {
  const PatternTree t;
  CHECK(expand_file_patterns({t("**/*.bvh")}) ==
        t.files({"a/x.bvh", "a/y.bvh", "a/z1.bvh", "b/w.bvh", "c/d/deep.bvh", "c/d/e/deeper.bvh",
                 "folder.bvh/inner.bvh", "top.bvh"}));
  CHECK(expand_file_patterns({t("c/**/deeper.bvh")}) == t.files({"c/d/e/deeper.bvh"}));
  CHECK(expand_file_patterns({t("c/d/e/**/deeper.bvh")}) == t.files({"c/d/e/deeper.bvh"}));  // zero folders
  CHECK(expand_file_patterns({t("**/d/*.bvh")}) == t.files({"c/d/deep.bvh"}));
  CHECK(expand_file_patterns({t("c/**/e/**/*.bvh")}) == t.files({"c/d/e/deeper.bvh"}));
  CHECK(expand_file_patterns({t("**/**/w.bvh")}) == t.files({"b/w.bvh"}));  // once, though found twice
}

TEST_CASE("expand_file_patterns: a leading dot is matched only when the pattern spells it") {
  const PatternTree t;
  CHECK(expand_file_patterns({t(".*.bvh")}) == t.files({".hidden.bvh"}));
  CHECK(expand_file_patterns({t(".git/*.bvh")}) == t.files({".git/ignored.bvh"}));
  CHECK(expand_file_patterns({t(".*/*.bvh")}) == t.files({".git/ignored.bvh"}));
  CHECK(expand_file_patterns({t("**/.hidden.bvh")}) == t.files({".hidden.bvh"}));
  CHECK(invalid_argument_of({t("?hidden.bvh")}) ==
        "input pattern '" + t("?hidden.bvh") + "' matches no file");
  CHECK(invalid_argument_of({t("[.]hidden.bvh")}) ==
        "input pattern '" + t("[.]hidden.bvh") + "' matches no file");
  CHECK(invalid_argument_of({t("*/ignored.bvh")}) ==
        "input pattern '" + t("*/ignored.bvh") + "' matches no file");
  // ** does not enter dot folders either.
  CHECK(invalid_argument_of({t("**/ignored.bvh")}) ==
        "input pattern '" + t("**/ignored.bvh") + "' matches no file");
}

TEST_CASE("expand_file_patterns: results are absolute, lexically normal, sorted and unique") {
  const PatternTree t;
  const auto files = expand_file_patterns({t("a/*.bvh"), t("**/x.bvh"), t("a/../a/./y.bvh"), t("b//w.bvh")});
  CHECK(files == t.files({"a/x.bvh", "a/y.bvh", "a/z1.bvh", "b/w.bvh"}));
  for (const fs::path& f : files) {
    CHECK(f.is_absolute());
    CHECK(f == f.lexically_normal());
  }
  CHECK(std::is_sorted(files.begin(), files.end()));

  // A relative pattern is taken from the working directory.
  const InFolder in(t.dir.path());
  const fs::path here = fs::current_path();
  CHECK(expand_file_patterns({"b/*.bvh", "./c/d/../d/deep.bvh", "top.bvh"}) ==
        std::vector<fs::path>{here / "b" / "w.bvh", here / "c" / "d" / "deep.bvh", here / "top.bvh"});
}

TEST_CASE("expand_file_patterns: a plain path names one file, symbolic links are followed") {
  const PatternTree t;
  CHECK(expand_file_patterns({t("c/d/e/deeper.bvh")}) == t.files({"c/d/e/deeper.bvh"}));
  CHECK(expand_file_patterns({t(".hidden.bvh")}) == t.files({".hidden.bvh"}));
  // Square brackets make a pattern: a file literally named "[x].bvh" is matched by "[[]x].bvh".
  t.dir.write("lit/[x].bvh", "x");
  CHECK(expand_file_patterns({t("lit/[[]x].bvh")}) == t.files({"lit/[x].bvh"}));

  std::error_code ec;
  fs::create_symlink(t.dir.path() / "a" / "x.bvh", t.dir.path() / "b" / "link.bvh", ec);
  if (!ec) fs::create_directory_symlink(t.dir.path() / "c" / "d", t.dir.path() / "b" / "dlink", ec);
  if (ec) {
    WARN("skipped: cannot create symbolic links here: " << ec.message());
    return;
  }
  CHECK(expand_file_patterns({t("b/*.bvh")}) == t.files({"b/link.bvh", "b/w.bvh"}));
  CHECK(expand_file_patterns({t("b/dlink/*.bvh")}) == t.files({"b/dlink/deep.bvh"}));
  CHECK(expand_file_patterns({t("b/link.bvh")}) == t.files({"b/link.bvh"}));

  // ** does not enter a link to a folder: a link to an ancestor would never end.
  fs::create_directory_symlink(t.dir.path(), t.dir.path() / "c" / "up", ec);
  REQUIRE_FALSE(ec);
  const auto all = expand_file_patterns({t("**/deeper.bvh")});
  CHECK(all == t.files({"c/d/e/deeper.bvh"}));
}

TEST_CASE("expand_file_patterns: a pattern matching nothing, a missing file and a folder are refused") {
  const PatternTree t;
  CHECK(invalid_argument_of({t("a/*.amc")}) == "input pattern '" + t("a/*.amc") + "' matches no file");
  CHECK(invalid_argument_of({t("nowhere/**/*.bvh")}) ==
        "input pattern '" + t("nowhere/**/*.bvh") + "' matches no file");
  // Folders only: ** alone and a * naming folders find no file.
  CHECK(invalid_argument_of({t("c/**")}) == "input pattern '" + t("c/**") + "' matches no file");
  CHECK(invalid_argument_of({t("c/*")}) == "input pattern '" + t("c/*") + "' matches no file");
  CHECK(invalid_argument_of({t("a/missing.bvh")}) == "no such input file: '" + t("a/missing.bvh") + "'");
  CHECK(invalid_argument_of({t("a")}) ==
        "input '" + t("a") + "' is a folder (give a pattern such as '" + t("a") + "/*.bvh')");
  CHECK(invalid_argument_of({t("folder.bvh")}) == "input '" + t("folder.bvh") +
                                                      "' is a folder (give a pattern such as '" +
                                                      t("folder.bvh") + "/*.bvh')");
  CHECK(invalid_argument_of({""}) == "an empty input pattern");
  // The first pattern finding nothing is named, even when others match.
  CHECK(invalid_argument_of({t("a/*.bvh"), t("b/*.amc"), t("c/*.amc")}) ==
        "input pattern '" + t("b/*.amc") + "' matches no file");
}

// ---- manifests ----------------------------------------------------------------------------------

TEST_CASE("manifest_line and parse_manifest_line round-trip every field on one line") {
  const ManifestRecord r = full_record();
  const std::string line = manifest_line(r);
  CHECK(line.find('\n') == std::string::npos);
  CHECK(line.find('\r') == std::string::npos);
  CHECK(line.front() == '{');
  CHECK(line.back() == '}');
  CHECK_THAT(line, Catch::Contains("\"solve.iterations\":12") &&
                       Catch::Contains("\"solve.converged\":true") &&
                       Catch::Contains("\"bytes\":123456789012"));
  check_same(parse_manifest_line(line), r);

  // An ok record with nothing optional set.
  const ManifestRecord bare = record("/in/a.bvh", "", "");
  check_same(parse_manifest_line(manifest_line(bare)), bare);
  CHECK(parse_manifest_line(manifest_line(bare)).ok());
  CHECK_FALSE(parse_manifest_line(line).ok());
}

TEST_CASE("a non-finite figure is written as null and reads back as NaN, keeping its line readable") {
  ManifestRecord r = record("/in/a.bvh", "2026-01-01T00:00:00Z", "h");
  r.figures = {{"x.nan", std::numeric_limits<double>::quiet_NaN()}, {"x.inf", HUGE_VAL}};
  const ManifestRecord back = parse_manifest_line(manifest_line(r));
  REQUIRE(back.figures.size() == 2);
  CHECK(std::isnan(std::get<double>(back.figures[0].second)));
  CHECK(std::isnan(std::get<double>(back.figures[1].second)));
}

TEST_CASE("figures keep their type through the manifest: a whole double is written with a fraction") {
  ManifestRecord r = record("/in/a.bvh", "2026-01-01T00:00:00Z", "h");
  r.figures = {{"x.two", 2.0}, {"x.minus", -3.0}, {"x.half", 2.5}, {"x.large", 1e22}};
  const std::string line = manifest_line(r);
  CHECK_THAT(line, Catch::Contains("\"x.two\":2.0,") && Catch::Contains("\"x.minus\":-3.0,"));
  const ManifestRecord back = parse_manifest_line(line);
  REQUIRE(back.figures.size() == 4);
  CHECK(back.figures[0].second == Figure{2.0});
  CHECK(back.figures[1].second == Figure{-3.0});
  CHECK(back.figures[2].second == Figure{2.5});
  CHECK(back.figures[3].second == Figure{1e22});  // written 1e+22: a double again
}

TEST_CASE("parse_manifest_line says what is wrong with a line") {
  CHECK_THROWS_AS(parse_manifest_line("{\"input\":\"/a\",\"stem\":"), std::runtime_error);  // torn
  CHECK_THROWS_WITH(parse_manifest_line("hello world"), Catch::Contains("not a JSON object"));
  CHECK_THROWS_WITH(parse_manifest_line("{\"stem\":\"a\",\"status\":\"ok\"}"),
                    Catch::Contains("no \"input\""));
  CHECK_THROWS_WITH(parse_manifest_line("{\"input\":\"/a\",\"stem\":\"a\",\"status\":\"maybe\"}"),
                    Catch::Contains("\"status\" is 'maybe', expected ok or failed"));
  CHECK_THROWS_WITH(parse_manifest_line("{\"input\":[1],\"stem\":\"a\",\"status\":\"ok\"}"),
                    Catch::Contains("\"input\" is not a string"));
  CHECK_THROWS_WITH(
      parse_manifest_line("{\"input\":\"/a\",\"stem\":\"a\",\"status\":\"ok\",\"figures\":[1]}"),
      Catch::Contains("\"figures\" is not an object"));
}

TEST_CASE("read_manifest skips torn and garbage lines, naming file:line, a missing file is empty") {
  TempDir dir;
  const ManifestRecord a = full_record();
  const ManifestRecord b = record("/in/b.bvh", "2026-01-01T00:00:01Z", "h2");
  const std::string torn = manifest_line(record("/in/c.bvh", "2026-01-01T00:00:02Z", "h3"));
  const fs::path file =
      dir.write("manifest.jsonl", manifest_line(a) + "\n" + "garbage, not JSON\n" + manifest_line(b) + "\n" +
                                      "\n" + torn.substr(0, torn.size() / 2));
  std::vector<std::string> problems;
  const std::vector<ManifestRecord> records = read_manifest(file, problems);
  REQUIRE(records.size() == 2);
  check_same(records[0], a);
  check_same(records[1], b);
  REQUIRE(problems.size() == 2);
  CHECK_THAT(problems[0], Catch::StartsWith(file.string() + ":2: not a manifest record"));
  CHECK_THAT(problems[1], Catch::StartsWith(file.string() + ":5: not a manifest record"));

  std::vector<std::string> none;
  CHECK(read_manifest(dir / "absent.jsonl", none).empty());
  CHECK(none.empty());
}

TEST_CASE("latest_records keeps the latest record per input, in order of first appearance") {
  const std::vector<ManifestRecord> records = {record("/in/a.bvh", "2026-01-01T00:00:05Z", "first"),
                                               record("/in/b.bvh", "2026-01-01T00:00:03Z", "b1"),
                                               record("/in/a.bvh", "2026-01-01T00:00:09Z", "latest"),
                                               record("/in/a.bvh", "2026-01-01T00:00:07Z", "older"),
                                               record("/in/b.bvh", "2026-01-01T00:00:03Z", "b2 same"),
                                               record("/in/c.bvh", "2026-01-01T00:00:01Z", "c"),
                                               record("/in/b.bvh", "2026-01-01T00:00:02Z", "b3 older")};
  const std::vector<ManifestRecord> latest = latest_records(records);
  REQUIRE(latest.size() == 3);
  CHECK(latest[0].input == "/in/a.bvh");
  CHECK(latest[0].host == "latest");
  CHECK(latest[1].input == "/in/b.bvh");
  CHECK(latest[1].host == "b2 same");  // equal timestamps: the later line wins
  CHECK(latest[2].input == "/in/c.bvh");
  CHECK(latest_records({}).empty());
}

TEST_CASE("settings_sha256 hashes sorted NAME=VALUE lines, whatever the order given") {
  const std::string h = settings_sha256({{"b", "two"}, {"a", "1"}});
  CHECK(h == settings_sha256({{"a", "1"}, {"b", "two"}}));
  CHECK(h == sha256_hex("a=1\nb=two\n"));
  CHECK(h != settings_sha256({{"a", "1"}, {"b", "three"}}));
  CHECK(h != settings_sha256({{"a", "1"}}));
  CHECK(settings_sha256({}) == kEmptyDigest);
  CHECK(std::regex_match(utc_timestamp(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
}

// ---- atomic files -------------------------------------------------------------------------------

TEST_CASE("written_files lists the completed writes in order, never a failed one") {
  TempDir dir;
  const std::size_t before = written_files().size();
  write_file_atomically(dir / "one.txt", [](std::ostream& os) { os << "1"; });
  CHECK_THROWS(write_file_atomically(dir / "broken.txt", [](std::ostream& os) {
    os << "half";
    throw std::runtime_error("writer broke");
  }));
  CHECK_THROWS(
      write_file_atomically(dir / "bad.txt", [](std::ostream& os) { os.setstate(std::ios::failbit); }));
  write_file_atomically(dir / "sub" / "two.txt", [](std::ostream& os) { os << "2"; });
  write_file_atomically(dir / "one.txt", [](std::ostream& os) { os << "1 again"; });
  CHECK(written_since(before) ==
        std::vector<fs::path>{dir / "one.txt", dir / "sub" / "two.txt", dir / "one.txt"});
  CHECK_FALSE(fs::exists(dir / "broken.txt"));
  CHECK_FALSE(fs::exists(dir / "bad.txt"));
}

TEST_CASE("remove_pending_temporaries removes a write's temporary, and that write then fails cleanly") {
  TempDir dir;
  const std::size_t before = written_files().size();
  const fs::path target = dir / "out.txt";

  // The temporary is unlinked while the stream still holds it, so the final rename finds nothing
  // to rename: the write throws naming the target, and the target is never created.
  std::vector<std::string> during, after;
  try {
    write_file_atomically(target, [&](std::ostream& os) {
      os << "partial";
      during = temporaries_in(dir.path());
      remove_pending_temporaries();
      after = temporaries_in(dir.path());
      os << " and more";
    });
    FAIL("the write succeeded without its temporary");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains("'" + target.string() + "'") && Catch::Contains("rename from"));
  }
  REQUIRE(during.size() == 1);
  CHECK_THAT(during[0], Catch::StartsWith(".out.txt.tmp."));
  CHECK(after.empty());
  CHECK_FALSE(fs::exists(target));
  CHECK(fs::is_empty(dir.path()));

  // An existing target keeps its content.
  dir.write("out.txt", "original");
  CHECK_THROWS_WITH(write_file_atomically(target,
                                          [](std::ostream& os) {
                                            os << "replacement";
                                            remove_pending_temporaries();
                                          }),
                    Catch::Contains(target.string()));
  CHECK(read_file(target) == "original");
  CHECK(temporaries_in(dir.path()).empty());

  // Every write in progress loses its temporary, here one nested in another.
  std::vector<std::string> both;
  std::string inner_error;
  CHECK_THROWS(write_file_atomically(dir / "outer.txt", [&](std::ostream& outer) {
    outer << "outer";
    try {
      write_file_atomically(dir / "inner.txt", [&](std::ostream& inner) {
        inner << "inner";
        both = temporaries_in(dir.path());
        remove_pending_temporaries();
      });
    } catch (const std::runtime_error& e) {
      inner_error = e.what();
    }
    CHECK(temporaries_in(dir.path()).empty());
  }));
  REQUIRE(both.size() == 2);
  CHECK_THAT(both[0], Catch::StartsWith(".inner.txt.tmp."));
  CHECK_THAT(both[1], Catch::StartsWith(".outer.txt.tmp."));
  CHECK_THAT(inner_error, Catch::Contains("inner.txt"));
  CHECK_FALSE(fs::exists(dir / "inner.txt"));
  CHECK_FALSE(fs::exists(dir / "outer.txt"));
  CHECK(written_since(before).empty());

  // Finished writes are no longer pending: their targets stay, and later writes work.
  write_file_atomically(dir / "done.txt", [](std::ostream& os) { os << "done"; });
  remove_pending_temporaries();
  CHECK(read_file(dir / "done.txt") == "done");
  CHECK(written_since(before) == std::vector<fs::path>{dir / "done.txt"});
}

// ---- graph variables ----------------------------------------------------------------------------

TEST_CASE("read_graph_variables lists declared variables in file order, none resolved") {
  TempDir dir;
  // A required variable without a value, defaults naming other variables, and nodes no registry
  // knows: none of it matters here.
  const fs::path file = dir.write("g.yaml", R"(version: 1
doc: For batch.
variables:
  input: {doc: "the clip", required: true}
  out:   {doc: "output folder", default: results}
  stem:  {default: "${input}"}
  output: {doc: where it goes, default: "${out}/${stem}.bvh", required: false}
  quiet:
nodes:
  a: {type: no.such.type, params: {path: "${undeclared}"}}
)");
  const std::vector<Variable> vars = read_graph_variables(file);
  REQUIRE(vars.size() == 5);
  CHECK(vars[0].name == "input");
  CHECK(vars[0].required);
  CHECK(vars[0].doc == "the clip");
  CHECK(vars[0].default_value.empty());
  CHECK(vars[0].where.to_string() == file.string() + ":4:3");
  CHECK(vars[1].name == "out");
  CHECK_FALSE(vars[1].required);
  CHECK(vars[1].default_value == "results");
  CHECK(vars[1].doc == "output folder");
  CHECK(vars[2].name == "stem");
  CHECK(vars[2].default_value == "${input}");
  CHECK(vars[2].doc.empty());
  CHECK(vars[3].name == "output");
  CHECK(vars[3].default_value == "${out}/${stem}.bvh");
  CHECK(vars[3].doc == "where it goes");
  CHECK_FALSE(vars[3].required);
  CHECK(vars[4].name == "quiet");
  CHECK_FALSE(vars[4].required);
  CHECK(vars[4].default_value.empty());
  CHECK(vars[4].where.to_string() == file.string() + ":8:3");

  CHECK(read_graph_variables(dir.write("none.yaml", "version: 1\nnodes:\n  a: {type: x}\n")).empty());
}

TEST_CASE("read_graph_variables refuses a malformed head with file:line") {
  TempDir dir;
  struct Case {
    const char* text;
    int line;
    const char* says;
  };
  const Case cases[] = {
      {"version: 1\nvariables:\n  input: {required: maybe}\n", 3,
       "'variables.input.required' must be true or false"},
      {"version: 1\nvariables:\n  input: {required: true, default: x}\n", 3,
       "is required, so it takes no default"},
      {"version: 1\nvariables:\n  input: {doc: a, dflt: x}\n", 3, "dflt"},
      {"version: 1\nvariables:\n  1st: {}\n", 3, "variable name '1st'"},
      {"version: 1\nvariables:\n  input: [a, b]\n", 3, "'variables.input' must be a map"},
      {"version: 1\nvariables: [a, b]\n", 2, "'variables' must be a map"},
      {"version: 1\nvariabels:\n  input: {}\n", 2, "variabels"},
      {"version: 2\nvariables:\n  input: {}\n", 1, "unsupported graph format version '2'"},
      {"doc: x\nvariables:\n  input: {}\n", 1, "missing 'version: 1'"},
      {"version: 1\nvariables:\n  input: {doc: \"open\n  out: {}\n", 5,
       "malformed YAML"},  // where the parser gives up
  };
  int index = 0;
  for (const Case& c : cases) {
    INFO(c.text);
    const fs::path file = dir.write("bad" + std::to_string(index++) + ".yaml", c.text);
    const std::string what = graph_error_of(file);
    CHECK_THAT(what, Catch::StartsWith(file.string() + ":" + std::to_string(c.line) + ":") &&
                         Catch::Contains(c.says));
  }
  CHECK_THAT(graph_error_of(dir / "absent.yaml"), Catch::Contains("absent.yaml: no such graph file"));
}
