#include "kg/graph/manifest.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "kg/base/atomic_file.hpp"
#include "kg/base/json.hpp"
#include "kg/graph/sha256.hpp"

namespace kg::graph {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;  // ordered: figures keep the order they were written in

const Json* member(const Json& object, const char* key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

std::string text_field(const Json& object, const char* key, bool required = true) {
  const Json* value = member(object, key);
  if (!value) {
    if (required) throw std::runtime_error(std::string("no \"") + key + "\"");
    return {};
  }
  if (!value->is_string()) throw std::runtime_error(std::string("\"") + key + "\" is not a string");
  return value->get<std::string>();
}

double number_field(const Json& object, const char* key) {
  const Json* value = member(object, key);
  if (!value || value->is_null()) return 0;
  if (!value->is_number()) throw std::runtime_error(std::string("\"") + key + "\" is not a number");
  return value->get<double>();
}

// As written: a whole number is an integer, one with a fraction or exponent a double, null the
// writer's non-finite number.
Figure figure_of(const Json& value) {
  if (value.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>();
  if (value.is_number_float()) return value.get<double>();
  if (value.is_number_integer()) {
    if (value.is_number_unsigned() &&
        value.get<std::uint64_t>() > std::uint64_t(std::numeric_limits<std::int64_t>::max()))
      throw std::runtime_error("a figure's whole number is too large");
    return value.get<std::int64_t>();
  }
  throw std::runtime_error("a figure is not a single value");
}

std::vector<ManifestFile> files_field(const Json& object, const char* key) {
  std::vector<ManifestFile> files;
  const Json* list = member(object, key);
  if (!list) return files;
  if (!list->is_array()) throw std::runtime_error(std::string("\"") + key + "\" is not a list");
  for (const Json& f : *list) {
    if (!f.is_object()) throw std::runtime_error(std::string("an entry of \"") + key + "\" is not an object");
    ManifestFile file;
    file.path = text_field(f, "path");
    file.sha256 = text_field(f, "sha256");
    if (const Json* bytes = member(f, "bytes")) {
      if (!bytes->is_number_unsigned()) throw std::runtime_error("\"bytes\" is not a whole number");
      file.bytes = bytes->get<std::uintmax_t>();
    }
    files.push_back(std::move(file));
  }
  return files;
}

// nlohmann's parse error without its "[json.exception.parse_error.101] " prefix.
std::string parse_problem(const nlohmann::json::parse_error& e) {
  const std::string what = e.what();
  const auto end = what.find("] ");
  return end == std::string::npos ? what : what.substr(end + 2);
}

void write_files(JsonWriter& w, const char* key, const std::vector<ManifestFile>& files) {
  w.key(key);
  w.begin_array();
  for (const ManifestFile& f : files) {
    w.begin_object();
    w.field("path", f.path);
    w.field("sha256", f.sha256);
    w.field("bytes", static_cast<std::int64_t>(f.bytes));
    w.end_object();
  }
  w.end_array();
}

ManifestRecord record_of(const Json& object) {
  if (!object.is_object()) throw std::runtime_error("not a JSON object");
  ManifestRecord r;
  r.input = text_field(object, "input");
  r.stem = text_field(object, "stem");
  r.item = text_field(object, "item", false);
  r.status = text_field(object, "status");
  if (r.status != "ok" && r.status != "failed")
    throw std::runtime_error("\"status\" is '" + r.status + "', expected ok or failed");
  r.message = text_field(object, "message", false);
  r.wall_seconds = number_field(object, "wall_seconds");
  r.graph_seconds = number_field(object, "graph_seconds");
  r.log = text_field(object, "log", false);
  r.outputs = files_field(object, "outputs");
  r.reads = files_field(object, "reads");
  if (const Json* figures = member(object, "figures")) {
    if (!figures->is_object()) throw std::runtime_error("\"figures\" is not an object");
    for (const auto& [key, value] : figures->items()) r.figures.emplace_back(key, figure_of(value));
  }
  r.input_sha256 = text_field(object, "input_sha256", false);
  r.graph_sha256 = text_field(object, "graph_sha256", false);
  r.settings_sha256 = text_field(object, "settings_sha256", false);
  r.finished_at = text_field(object, "finished_at", false);
  r.host = text_field(object, "host", false);
  r.shard = text_field(object, "shard", false);
  return r;
}

}  // namespace

std::string manifest_line(const ManifestRecord& r) {
  std::ostringstream os;
  JsonWriter w(os, 0);
  w.begin_object();
  w.field("input", r.input);
  w.field("stem", r.stem);
  w.field("item", r.item);
  w.field("status", r.status);
  w.field("message", r.message);
  w.field("wall_seconds", r.wall_seconds);
  w.field("graph_seconds", r.graph_seconds);
  w.field("log", r.log);
  write_files(w, "outputs", r.outputs);
  write_files(w, "reads", r.reads);
  w.key("figures");
  w.begin_object();
  for (const auto& [key, figure] : r.figures) w.field(key, figure);
  w.end_object();
  w.field("input_sha256", r.input_sha256);
  w.field("graph_sha256", r.graph_sha256);
  w.field("settings_sha256", r.settings_sha256);
  w.field("finished_at", r.finished_at);
  w.field("host", r.host);
  w.field("shard", r.shard);
  w.end_object();
  std::string line = std::move(os).str();
  // The writer puts no newline inside a one-line object; strings escape theirs.
  line.erase(std::remove(line.begin(), line.end(), '\n'), line.end());
  return line;
}

ManifestRecord parse_manifest_line(const std::string& line) {
  Json object;
  try {
    object = Json::parse(line);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error("not a JSON object: " + parse_problem(e));
  }
  return record_of(object);
}

std::vector<ManifestRecord> read_manifest(const fs::path& file, std::vector<std::string>& problems) {
  std::vector<ManifestRecord> records;
  std::ifstream in(file, std::ios::binary);
  if (!in) return records;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    try {
      records.push_back(parse_manifest_line(line));
    } catch (const std::exception& e) {
      problems.push_back(file.string() + ":" + std::to_string(number) + ": not a manifest record (" +
                         e.what() + "); skipped, so its item runs again");
    }
  }
  return records;
}

std::vector<ManifestRecord> latest_records(const std::vector<ManifestRecord>& records) {
  std::vector<ManifestRecord> latest;
  std::map<std::string, std::size_t> index;
  for (const ManifestRecord& r : records) {
    const auto [it, fresh] = index.emplace(r.input, latest.size());
    if (fresh) {
      latest.push_back(r);
    } else if (r.finished_at >= latest[it->second].finished_at) {
      latest[it->second] = r;
    }
  }
  return latest;
}

std::string settings_sha256(const std::vector<std::pair<std::string, std::string>>& settings) {
  std::vector<std::pair<std::string, std::string>> sorted = settings;
  std::sort(sorted.begin(), sorted.end());
  Sha256 s;
  for (const auto& [name, value] : sorted) {
    s.update(name);
    s.update("=", 1);
    s.update(value);
    s.update("\n", 1);
  }
  return s.hex();
}

void write_batch_identity(const fs::path& file, const BatchIdentity& identity) {
  write_file_atomically(file, [&](std::ostream& os) {
    JsonWriter w(os);
    w.begin_object();
    w.field("graph", identity.graph);
    w.field("graph_sha256", identity.graph_sha256);
    w.field("settings_sha256", identity.settings_sha256);
    w.end_object();
    os << '\n';
  });
}

BatchIdentity read_batch_identity(const fs::path& file) {
  try {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::runtime_error(std::string("cannot open it: ") + std::strerror(errno));
    Json object;
    try {
      object = Json::parse(in);
    } catch (const nlohmann::json::parse_error& e) {
      throw std::runtime_error(parse_problem(e));
    }
    if (!object.is_object()) throw std::runtime_error("not a JSON object");
    return {text_field(object, "graph"), text_field(object, "graph_sha256"),
            text_field(object, "settings_sha256")};
  } catch (const std::exception& e) {
    throw std::runtime_error(file.string() + ": not a batch description: " + e.what());
  }
}

std::string utc_timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

}  // namespace kg::graph
