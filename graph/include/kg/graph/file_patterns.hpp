// Input files named by shell-style patterns (batch --inputs), expanded the same way on every
// machine so that shards of one batch agree on the item list.
//
//   auto files = expand_file_patterns({"data/cmu/**/*.bvh", "extra/walk.amc"});
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kg::graph {

// Patterns: `*`, `?` and `[...]` match within one path component (a leading '.' only when the
// pattern spells it); a component `**` matches any number of folders, none included, without
// entering symbolic links to folders (a link to an ancestor would never end). A pattern
// without wildcards, or one matching nothing that names an existing file as written
// ("take[1].bvh"), names that file. Returns the regular files matched (symbolic links followed),
// absolute and lexically normal, sorted by path, each once. Throws std::invalid_argument naming
// the first pattern that matches no file.
std::vector<std::filesystem::path> expand_file_patterns(const std::vector<std::string>& patterns);

}  // namespace kg::graph
