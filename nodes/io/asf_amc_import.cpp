// ASF/AMC import to skeleton.hpp's conventions, and the extension dispatch of import_motion.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"

namespace kg::io {

namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

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

ImportedMotion import_motion(const std::string& path, const std::string& skeleton_path,
                             const ImportOptions& options) {
  const std::string ext = lower_extension(path);
  if (ext == ".bvh") {
    if (!skeleton_path.empty()) {
      throw std::invalid_argument(path +
                                  ": a BVH file holds its own skeleton; expected skeleton \"\", got \"" +
                                  skeleton_path + "\"");
    }
    return import_bvh(path, options);
  }
  if (ext == ".amc") {
    std::string asf = skeleton_path;
    std::vector<std::string> notes;
    if (asf.empty()) {
      asf = guess_asf_for_amc(path);
      if (asf.empty()) {
        throw std::invalid_argument(
            path +
            ": an AMC file needs its skeleton: set skeleton to the .asf file (none found "
            "by the subject prefix of the name, e.g. 16_15.amc -> 16.asf)");
      }
      notes.push_back(file_name_of(path) + ": skeleton not given; using " + asf +
                      " (the subject prefix of the name)");
    }
    ImportedMotion out = import_asf_amc(asf, path, options);
    out.notes.insert(out.notes.begin(), notes.begin(), notes.end());
    return out;
  }
  throw std::invalid_argument(path + ": expected a .bvh or .amc file, got extension \"" + ext + "\"");
}

}  // namespace kg::io
