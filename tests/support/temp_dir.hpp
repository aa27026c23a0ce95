// Test support: a scratch directory removed at scope end, and reading a whole file.
//
//   kg::test::TempDir dir;
//   const fs::path in = dir.write("sub/clip.bvh", text);   // parent folders created
//   CHECK(kg::test::read_file(dir / "out.txt") == "42\n");
#pragma once

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace kg::test {

namespace fs = std::filesystem;

// A fresh directory under the system temp folder, removed with everything in it on destruction.
// Unique per process and instance, so test executables running in parallel never share one.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("kg_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

  // Writes `text` (bytes as given) to `name` under the directory, creating its parent folders;
  // returns the file's path.
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path file = path_ / name;
    fs::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

 private:
  fs::path path_;
};

// The whole file as bytes; "" when it cannot be read.
inline std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

}  // namespace kg::test
