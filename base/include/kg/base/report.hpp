// A JSON document kept as a value: what a solver outputs as its report (kg.Report on a port) for
// a sink node to write (io.write_report), so that solvers write no files (DESIGN.md 13). Built
// with a JsonWriter over it; written with exactly the text that JsonWriter would have written to
// a stream (json.hpp: nlohmann's layout, shortest round-trip doubles). Immutable once built;
// copies share the document.
//
//   Report report;
//   { JsonWriter w(report); w.begin_object(); w.field("converged", true); w.end_object(); }
//   report.write(std::cout);   // {\n  "converged": true\n}\n
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace kg {

class Report {
 public:
  Report() = default;  // empty: no document

  bool empty() const { return !doc_; }
  // The document as JsonWriter(os, indent) writes it (a container ends its line when indent > 0);
  // nothing when empty.
  void write(std::ostream& os, int indent = 2) const;
  std::string text(int indent = 2) const;
  // The strings of the document's top-level array `key` (other elements skipped); empty when the
  // document is empty or has no such array.
  std::vector<std::string> strings(std::string_view key) const;

 private:
  friend class JsonWriter;
  struct Document;                       // the nlohmann::ordered_json (json.cpp)
  std::shared_ptr<const Document> doc_;  // shared by copies, never modified
};

}  // namespace kg
