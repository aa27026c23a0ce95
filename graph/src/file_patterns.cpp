#include "kg/graph/file_patterns.hpp"

#include <fnmatch.h>

#include <algorithm>
#include <set>
#include <stdexcept>
#include <system_error>

#include "kg/base/text.hpp"

namespace kg::graph {
namespace {

namespace fs = std::filesystem;

bool has_wildcard(const std::string& component) {
  return component.find_first_of("*?[") != std::string::npos;
}

void walk(const fs::path& dir, const std::vector<std::string>& components, std::size_t index,
          std::set<fs::path>& found) {
  std::error_code ec;
  if (index == components.size()) {
    if (fs::is_regular_file(dir, ec)) found.insert(dir);
    return;
  }
  const std::string& component = components[index];
  if (component == "**") {
    walk(dir, components, index + 1, found);
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      // Links are not followed, as bash's globstar: a link to an ancestor would recurse forever.
      if (name.front() != '.' && !it->is_symlink(ec) && it->is_directory(ec))
        walk(it->path(), components, index, found);
    }
    return;
  }
  if (!has_wildcard(component)) {
    walk(dir / component, components, index + 1, found);
    return;
  }
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (::fnmatch(component.c_str(), name.c_str(), FNM_PERIOD) == 0)
      walk(it->path(), components, index + 1, found);
  }
}

}  // namespace

std::vector<fs::path> expand_file_patterns(const std::vector<std::string>& patterns) {
  std::set<fs::path> all;
  for (const std::string& pattern : patterns) {
    if (pattern.empty()) throw std::invalid_argument("an empty input pattern");
    const fs::path absolute = fs::absolute(fs::path(pattern)).lexically_normal();
    fs::path base = absolute.root_path();
    std::vector<std::string> components;
    bool wild = false;
    for (const fs::path& part : absolute.relative_path()) {
      const std::string text = part.string();
      if (text.empty()) continue;
      wild = wild || has_wildcard(text);
      if (wild) {
        components.push_back(text);
      } else {
        base /= part;
      }
    }
    std::set<fs::path> found;
    walk(base, components, 0, found);
    std::error_code ec;
    if (found.empty() && wild && fs::is_regular_file(absolute, ec)) found.insert(absolute);  // take[1].bvh
    if (found.empty()) {
      if (!wild && fs::is_directory(absolute, ec))
        throw std::invalid_argument("input " + text::in_quotes(pattern) +
                                    " is a folder (give a pattern such as '" + pattern + "/*.bvh')");
      throw std::invalid_argument(wild ? "input pattern " + text::in_quotes(pattern) + " matches no file"
                                       : "no such input file: " + text::in_quotes(pattern));
    }
    all.insert(found.begin(), found.end());
  }
  return {all.begin(), all.end()};
}

}  // namespace kg::graph
