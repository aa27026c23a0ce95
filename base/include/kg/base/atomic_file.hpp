// Files of a run: inputs are read through read_input_file, outputs written through
// write_file_atomically, so that readers see either the old content or the whole new content of
// an output, never a part (data goes to a temporary file beside the target, is flushed, then
// renamed over it), and no output ever replaces a file the process has read as an input (the
// graph file, a clip, a skeleton found by guessing, ...), whatever path leads to it.
//
//   std::string text = read_input_file("walk.bvh", "BVH file");
//   write_file_atomically("out/walk.bvh", [&](std::ostream& os) { write_bvh(os, motion); });
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace kg {

// The whole content of `path` as text, which from now on this process refuses to overwrite. A
// UTF-8 byte-order mark is dropped. Throws Error located at the file: "no such <what>", "<what>
// expected, got a directory", "cannot open <what>"; at file:1:1 for UTF-16 and UTF-32 text (told by
// its byte-order mark), which every reader here would take for binary.
std::string read_input_file(const std::filesystem::path& path, const std::string& what);

// The content of an input file as read_input_file reads it (same checks, same messages, from now
// on refused as an output), without a copy: a regular file is mapped read-only, so a large clip
// parses straight from the page cache; anything else (a pipe, a special file) is read into memory.
// Move-only; text() is valid while this object lives. A file truncated by another process while
// mapped faults on access (SIGBUS): readers of files being rewritten use read_input_file.
class InputText {
 public:
  InputText() = default;
  InputText(InputText&& other) noexcept;
  InputText& operator=(InputText&& other) noexcept;
  InputText(const InputText&) = delete;
  InputText& operator=(const InputText&) = delete;
  ~InputText();

  std::string_view text() const { return text_; }

 private:
  friend InputText map_input_file(const std::filesystem::path& path, const std::string& what);
  void* map_ = nullptr;  // the mapping, when the file is mapped
  std::size_t map_size_ = 0;
  std::string owned_;  // the content, when it is not
  std::string_view text_;
};
InputText map_input_file(const std::filesystem::path& path, const std::string& what);

// Whether `path` names a file read through read_input_file (by any path leading to it).
bool is_input_file(const std::filesystem::path& path);

// Creates missing parent directories. Refuses (std::runtime_error naming the path) a target that
// is an input file. If `write` throws or the stream fails, the temporary file is removed, the
// target is untouched, and the error propagates (std::runtime_error naming the path).
void write_file_atomically(const std::filesystem::path& target,
                           const std::function<void(std::ostream&)>& write);

// Removes the temporary file of every write_file_atomically call still in progress in this process,
// without locks or allocation, so a SIGINT/SIGTERM handler may call it: an interrupted process
// leaves no partial output beside its targets.
void remove_pending_temporaries() noexcept;

// The targets write_file_atomically has completed in this process, in order (a batch runs each
// item in its own process, so these are the item's outputs).
std::vector<std::filesystem::path> written_files();

// Removes the targets write_file_atomically has completed in this process (the first 256), without
// locks or allocation, for a signal handler of a process doing one unit of work: interrupted, it
// leaves none of that work's outputs.
void remove_written_files() noexcept;

// The files read through read_input_file in this process, by canonical path, sorted.
std::vector<std::filesystem::path> input_files_read();

// Empties the lists above (files written and read) for a forked child that starts a unit of work
// of its own: the files its parent wrote are not the child's outputs, and an interrupted child
// must not remove them.
void forget_files_of_parent_process();

}  // namespace kg
