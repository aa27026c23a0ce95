// Test support: a batch manifest (one JSON object per line) read independently of the code that
// wrote it, keyed by each record's "item".
//
//   const auto records = kg::test::manifest_by_item(out / "manifest.jsonl");
//   CHECK(records.at("16_15")["status"].as<std::string>() == "ok");
#pragma once

#include <filesystem>
#include <map>
#include <sstream>
#include <string>

#include <yaml-cpp/yaml.h>

#include "temp_dir.hpp"

namespace kg::test {

inline std::map<std::string, YAML::Node> manifest_by_item(const std::filesystem::path& file) {
  std::map<std::string, YAML::Node> records;
  std::istringstream lines(read_file(file));
  for (std::string line; std::getline(lines, line);) {
    const YAML::Node r = YAML::Load(line);
    records[r["item"].as<std::string>()] = r;
  }
  return records;
}

}  // namespace kg::test
