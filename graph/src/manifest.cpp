#include "kg/graph/manifest.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
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

std::string text_field(const YAML::Node& object, const char* key, bool required = true) {
  const YAML::Node value = object[key];
  if (!value) {
    if (required) throw std::runtime_error(std::string("no \"") + key + "\"");
    return {};
  }
  if (!value.IsScalar()) throw std::runtime_error(std::string("\"") + key + "\" is not a string");
  return value.Scalar();
}

double number_field(const YAML::Node& object, const char* key) {
  const YAML::Node value = object[key];
  if (!value || value.IsNull()) return 0;
  return value.as<double>();
}

// JSON read through YAML: a quoted scalar is a string; a plain one a bool, whole number or number.
Figure figure_of(const YAML::Node& value) {
  if (value.IsNull()) return std::numeric_limits<double>::quiet_NaN();  // the writer's non-finite number
  if (!value.IsScalar()) throw std::runtime_error("a figure is not a single value");
  const std::string& text = value.Scalar();
  if (value.Tag() == "!") return text;
  if (text == "true") return true;
  if (text == "false") return false;
  if (text.find_first_of(".eE") == std::string::npos) return value.as<std::int64_t>();
  return value.as<double>();
}

std::vector<ManifestFile> files_field(const YAML::Node& object, const char* key) {
  std::vector<ManifestFile> files;
  const YAML::Node list = object[key];
  if (!list) return files;
  if (!list.IsSequence()) throw std::runtime_error(std::string("\"") + key + "\" is not a list");
  for (const YAML::Node& f : list) {
    ManifestFile file;
    file.path = text_field(f, "path");
    file.sha256 = text_field(f, "sha256");
    file.bytes = f["bytes"] ? f["bytes"].as<std::uintmax_t>() : 0;
    files.push_back(std::move(file));
  }
  return files;
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

ManifestRecord record_of(const YAML::Node& object) {
  if (!object.IsMap()) throw std::runtime_error("not a JSON object");
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
  if (const YAML::Node figures = object["figures"]) {
    if (!figures.IsMap()) throw std::runtime_error("\"figures\" is not an object");
    for (const auto& kv : figures) r.figures.emplace_back(kv.first.Scalar(), figure_of(kv.second));
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
  try {
    return record_of(YAML::Load(line));
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(e.msg);
  }
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
    const YAML::Node object = YAML::LoadFile(file.string());
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
