// Writes a file so that readers see either the old content or the whole new content, never a
// part: data goes to a temporary file beside the target, is flushed, then renamed over it.
//
//   write_file_atomically("out/walk.bvh", [&](std::ostream& os) { write_bvh(os, motion); });
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>

namespace kg::graph {

// Creates missing parent directories. If `write` throws or the stream fails, the temporary
// file is removed, the target is untouched, and the error propagates (std::runtime_error naming
// the path). 
void write_file_atomically(const std::filesystem::path& target, const std::function<void(std::ostream&)>& write);

}  // namespace kg::graph
