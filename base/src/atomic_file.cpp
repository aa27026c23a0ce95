#include "kg/base/atomic_file.hpp"
#include "kg/base/text.hpp"

#include "kg/base/error.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fstream>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>

namespace kg {

namespace fs = std::filesystem;

namespace {

// Every input file read by this process, by canonical path (and (device, inode) through
// fs::equivalent when comparing), guarded for readers on several threads.
struct InputFiles {
  std::mutex mutex;
  std::set<fs::path> paths;
};
InputFiles& input_files() {
  static InputFiles files;
  return files;
}

// Unique within the machine for this process's lifetime: several threads or processes may write
// beside the same target at once.
fs::path temporary_beside(const fs::path& target) {
  static std::atomic<unsigned long> counter{0};
  std::string name = ".";
  name += target.filename().string();
  name += ".tmp.";
  name += std::to_string(::getpid());
  name += '.';
  name += std::to_string(counter.fetch_add(1));
  return target.parent_path() / name;
}

// The temporaries being written, for remove_pending_temporaries in a signal handler: fixed slots,
// each free (0), being claimed (1) or holding a path (2). A write finding no free slot is not
// tracked, which only matters if the process is interrupted during it.
struct PendingSlot {
  std::atomic<int> state{0};
  char path[4096];
};
std::array<PendingSlot, 64> pending_slots;
// The same for targets written, once renamed into place.
std::array<PendingSlot, 256> written_slots;

template <std::size_t N>
PendingSlot* track(std::array<PendingSlot, N>& slots, const fs::path& file) {
  const std::string& text = file.native();
  if (text.size() >= sizeof(PendingSlot::path)) return nullptr;
  for (PendingSlot& slot : slots) {
    int expected = 0;
    if (!slot.state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(slot.path, text.c_str(), text.size() + 1);
    slot.state.store(2);
    return &slot;
  }
  return nullptr;
}

// Lock- and allocation-free: called from signal handlers.
template <std::size_t N>
void unlink_tracked(std::array<PendingSlot, N>& slots) noexcept {
  for (PendingSlot& slot : slots) {
    if (slot.state.load() == 2) ::unlink(slot.path);
  }
}

struct WrittenFiles {
  std::mutex mutex;
  std::vector<fs::path> paths;
};
WrittenFiles& written() {
  static WrittenFiles files;
  return files;
}

// Refuses text in UTF-16 or UTF-32 (by its byte-order mark); drops a UTF-8 byte-order mark.
void check_encoding(std::string_view& text, const std::string& path, const std::string& what) {
  const auto starts = [&](std::string_view mark) { return text.substr(0, mark.size()) == mark; };
  using namespace std::string_view_literals;
  for (const auto& [mark, encoding] :
       {std::pair{"\xff\xfe\0\0"sv, "UTF-32 (little-endian)"},
        std::pair{"\0\0\xfe\xff"sv, "UTF-32 (big-endian)"}, std::pair{"\xff\xfe"sv, "UTF-16 (little-endian)"},
        std::pair{"\xfe\xff"sv, "UTF-16 (big-endian)"}}) {
    if (starts(mark))
      throw Error(what + " is " + encoding + " text (its first bytes are the byte-order mark " +
                      text::excerpt(mark) + "); expected UTF-8 or ASCII: save it as UTF-8",
                  {path, 1, 1});
  }
  if (starts("\xef\xbb\xbf")) text.remove_prefix(3);
}

void remove_quietly(const fs::path& p) {
  std::error_code ec;
  fs::remove(p, ec);
}

}  // namespace

InputText::InputText(InputText&& other) noexcept {
  *this = std::move(other);
}

InputText& InputText::operator=(InputText&& other) noexcept {
  if (this == &other) return *this;
  if (map_ != nullptr) ::munmap(map_, map_size_);
  if (other.map_ != nullptr) {
    text_ = other.text_;
  } else {  // the view points into other's string: where it starts in that string is kept
    const std::size_t offset =
        other.text_.empty() ? 0 : static_cast<std::size_t>(other.text_.data() - other.owned_.data());
    owned_ = std::move(other.owned_);
    text_ = std::string_view(owned_).substr(offset, other.text_.size());
  }
  map_ = std::exchange(other.map_, nullptr);
  map_size_ = std::exchange(other.map_size_, 0);
  other.text_ = {};
  return *this;
}

InputText::~InputText() {
  if (map_ != nullptr) ::munmap(map_, map_size_);
}

InputText map_input_file(const fs::path& path, const std::string& what) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error("no such " + what, {path.string()});
  if (fs::is_directory(path, ec)) throw Error(what + " expected, got a directory", {path.string()});
  InputText input;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error("cannot open " + what + ": " + std::strerror(errno), {path.string()});
  const std::unique_ptr<const int, void (*)(const int*)> close_fd(
      &fd, [](const int* open_fd) { ::close(*open_fd); });
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
    void* map =
        ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (map != MAP_FAILED) {
      input.map_ = map;
      input.map_size_ = static_cast<std::size_t>(st.st_size);
      input.text_ = std::string_view(static_cast<const char*>(map), input.map_size_);
    }
  }
  if (input.map_ == nullptr) {  // not a regular file, or one that cannot be mapped: read it
    // From the same descriptor: a FIFO opened again would lose its writer in between.
    char chunk[1 << 16];
    for (;;) {
      const ssize_t got = ::read(fd, chunk, sizeof chunk);
      if (got == 0) break;
      if (got < 0) {
        if (errno == EINTR) continue;
        throw Error("cannot read " + what + ": " + std::strerror(errno), {path.string()});
      }
      input.owned_.append(chunk, static_cast<std::size_t>(got));
    }
    input.text_ = input.owned_;
  }
  check_encoding(input.text_, path.string(), what);
  const fs::path canonical = fs::weakly_canonical(path, ec);
  InputFiles& files = input_files();
  const std::lock_guard<std::mutex> lock(files.mutex);
  files.paths.insert(ec ? path : canonical);
  return input;
}

std::string read_input_file(const fs::path& path, const std::string& what) {
  return std::string(map_input_file(path, what).text());
}

bool is_input_file(const fs::path& path) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(path, ec);
  InputFiles& files = input_files();
  const std::lock_guard<std::mutex> lock(files.mutex);
  if (files.paths.count(ec ? path : canonical)) return true;
  for (const fs::path& input : files.paths)  // hard links and other spellings of one file
    if (fs::equivalent(input, path, ec)) return true;
  return false;
}

void write_file_atomically(const fs::path& target, const std::function<void(std::ostream&)>& write) {
  const std::string what = "cannot write '" + target.string() + "'";
  if (target.empty() || !target.has_filename()) throw std::runtime_error(what + ": not a file name");
  if (is_input_file(target))
    throw std::runtime_error(what + ": it is an input of this run and is never overwritten");

  std::error_code ec;
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec)
      throw std::runtime_error(what + ": cannot create directory '" + target.parent_path().string() +
                               "': " + ec.message());
  }
  if (fs::is_directory(target, ec)) throw std::runtime_error(what + ": it is a directory");

  const fs::path temp = temporary_beside(target);
  PendingSlot* const pending = track(pending_slots, temp);
  struct Untrack {
    PendingSlot* slot;
    ~Untrack() {
      if (slot) slot->state.store(0);
    }
  } untrack{pending};
  try {
    std::ofstream os(temp, std::ios::binary | std::ios::trunc);
    if (!os) throw std::runtime_error(what + ": cannot create temporary file '" + temp.string() + "'");
    try {
      write(os);
    } catch (const std::exception& e) {
      os.close();
      remove_quietly(temp);
      std::throw_with_nested(std::runtime_error(what + ": " + e.what()));
    } catch (...) {
      os.close();
      remove_quietly(temp);
      std::throw_with_nested(std::runtime_error(what + ": unknown error"));
    }
    os.flush();
    if (!os) throw std::runtime_error(what + ": write error (disk full?)");
    os.close();
    if (os.fail()) throw std::runtime_error(what + ": error closing the temporary file");

    // Keep the permissions of a file being replaced.
    if (fs::exists(target, ec)) {
      const auto perms = fs::status(target, ec).permissions();
      if (!ec) fs::permissions(temp, perms, ec);
    }
    fs::rename(temp, target, ec);
    if (ec) throw std::runtime_error(what + ": rename from '" + temp.string() + "' failed: " + ec.message());
  } catch (...) {
    remove_quietly(temp);
    throw;
  }
  WrittenFiles& files = written();
  const std::lock_guard<std::mutex> lock(files.mutex);
  const bool again = std::find(files.paths.begin(), files.paths.end(), target) != files.paths.end();
  if (!again) track(written_slots, fs::absolute(target, ec));
  files.paths.push_back(target);
}

void remove_written_files() noexcept {
  unlink_tracked(written_slots);
}

std::vector<fs::path> input_files_read() {
  InputFiles& files = input_files();
  const std::lock_guard<std::mutex> lock(files.mutex);
  return {files.paths.begin(), files.paths.end()};
}

void remove_pending_temporaries() noexcept {
  unlink_tracked(pending_slots);
}

void forget_files_of_parent_process() {
  {
    WrittenFiles& files = written();
    const std::lock_guard<std::mutex> lock(files.mutex);
    files.paths.clear();
    for (PendingSlot& slot : written_slots) slot.state.store(0);
  }
  InputFiles& files = input_files();
  const std::lock_guard<std::mutex> lock(files.mutex);
  files.paths.clear();
}

std::vector<fs::path> written_files() {
  WrittenFiles& files = written();
  const std::lock_guard<std::mutex> lock(files.mutex);
  return files.paths;
}

}  // namespace kg
