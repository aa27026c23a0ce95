#include "kg/base/error.hpp"

#include "kg/base/text.hpp"

#include <algorithm>
#include <cctype>
#include <string_view>

namespace kg {

std::string SourceLocation::to_string() const {
  std::string s = text::shown_path(file);
  if (line > 0) {
    if (!s.empty()) s += ':';
    s += std::to_string(line);
    if (column > 0) s += ':' + std::to_string(column);
  }
  return s;
}

namespace {

std::string compose(const std::string& message, const SourceLocation& where) {
  std::string place = where.to_string();
  return place.empty() ? message : place + ": " + message;
}

std::string lowered(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Optimal string alignment distance (Levenshtein plus adjacent transpositions): "parmas" is one
// edit from "params", as a typist would count it.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::size_t> prev2(m + 1), prev(m + 1), cur(m + 1);
  for (std::size_t j = 0; j <= m; ++j) prev[j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        cur[j] = std::min(cur[j], prev2[j - 2] + 1);
    }
    std::swap(prev2, prev);
    std::swap(prev, cur);
  }
  return prev[m];
}

}  // namespace

Error::Error(const std::string& message, SourceLocation where)
    : std::runtime_error(compose(message, where)), message_(message), where_(std::move(where)) {}

std::string nearest_name(const std::string& name, const std::vector<std::string>& candidates) {
  if (name.empty()) return {};
  const std::string key = lowered(name);
  std::string best;
  std::size_t best_score = static_cast<std::size_t>(-1);
  for (const std::string& candidate : candidates) {
    if (candidate.empty()) continue;
    const std::string c = lowered(candidate);
    std::size_t d = edit_distance(key, c);
    // A name missing its stage ("import_bvh" for "io.import_bvh") or with one added is close
    // however many characters differ.
    const bool part =
        key.size() >= 3 && (c.find(key) != std::string::npos || key.find(c) != std::string::npos);
    const std::size_t longest = std::max(key.size(), c.size());
    const std::size_t allowed = std::max<std::size_t>(1, (longest + 2) / 3);
    if (d > allowed && !part) continue;
    // Rank partial matches just behind equally distant plain matches.
    const std::size_t score = 2 * d + (d > allowed ? 1 : 0);
    if (score < best_score) {
      best_score = score;
      best = candidate;
    }
  }
  return best;
}

}  // namespace kg
