// `kinegraph batch ... --slurm SCRIPT`: the batch as Slurm jobs. Writes (batch.cpp writes
// DIR/batch.json beside them)
//   DIR/inputs.txt     the inputs, frozen, so every array task sees the same sorted list
//   SCRIPT             an sbatch array job: task I runs `kinegraph batch ... --shard I/N`
//   SCRIPT's merge     beside SCRIPT, "<name>.merge<ext>": `kinegraph merge DIR`, to submit with
//                      --dependency=afterany:<array job id>
// and with --submit submits both (sbatch must be on PATH). Task logs go to DIR/slurm/.
#pragma once

#include <filesystem>
#include <vector>

#include "options.hpp"

namespace kg::app {

// `graph`, `dir`, `inputs` and `executable` absolute. Returns the exit code; throws Failure.
int write_slurm_jobs(const Options& o, const std::filesystem::path& graph, const std::filesystem::path& dir,
                     const std::vector<std::filesystem::path>& inputs,
                     const std::filesystem::path& executable);

// The merge script written beside `script`.
std::filesystem::path merge_script_path(const std::filesystem::path& script);

}  // namespace kg::app
