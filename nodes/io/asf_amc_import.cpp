// ASF/AMC import to skeleton.hpp's conventions.
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "kg/io/asf_amc.hpp"

namespace kg::io {

namespace {

std::string file_name_of(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

}  // namespace

ImportedMotion import_asf_amc(const std::string& asf_path, const std::string& amc_path,
                              const ImportOptions& options) {
  const AsfSkeleton asf = read_asf(asf_path);
  ImportedMotion out{read_amc(amc_path, asf), asf.notes};
  const std::string amc_name = file_name_of(amc_path);
  if (options.fps <= 0) {
    std::ostringstream s;
    s << amc_name << ": AMC files carry no frame rate; taken as " << kAmcDefaultFps
      << " fps (CMU's capture rate); set fps to override";
    out.notes.push_back(s.str());
  }
  // The AMC's lengths are the ASF's, so the ASF's :units decide both. With an fps option the
  // file has no rate to report as overridden.
  std::vector<std::string> notes =
      apply_import_options(out.motion, options, options.fps > 0 ? 0.0 : kAmcDefaultFps,
                           file_name_of(asf_path), asf.declared_metres_per_unit().value_or(0.0));
  out.notes.insert(out.notes.end(), notes.begin(), notes.end());
  return out;
}

std::string guess_asf_for_amc(const std::string& amc_path) {
  const std::filesystem::path p(amc_path);
  const std::string stem = p.stem().string();
  const std::size_t cut = stem.find('_');
  if (cut == std::string::npos || cut == 0) return {};
  const std::filesystem::path candidate = p.parent_path() / (stem.substr(0, cut) + ".asf");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(candidate, ec)) return {};
  return candidate.string();
}

}  // namespace kg::io
