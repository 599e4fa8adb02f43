// lodforge: one binary, subcommands registered in one explicit list.
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>
#include <filesystem>
#include <new>
#include <vector>
#include <malloc.h>
#include <iostream>
#include <gdal_priv.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CGAL/version.h>
#include <Eigen/Core>
#include <ceres/version.h>
#include <opencv2/core/version.hpp>
#include <tbb/version.h>

#include "commands/commands.hpp"
#include "io/atomic_file.hpp"
#include "io/errors.hpp"

namespace {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(int, char**);
};

const Command commands[] = {
    {"run", "process an area described by a YAML job: tiles, checkpoints, resume, shards", lodforge::run_job},
    {"merge", "combine a run's per-tile files into one file per format", lodforge::run_merge},
    {"eval", "score footprints against ground truth (IoU, F1, C-IoU, N-ratio, PoLiS, Hausdorff)", lodforge::run_eval},
    {"config", "print the full default job (--defaults)", lodforge::run_config},
    {"regularize", "LOD0 footprints of every building in a segmentation raster", lodforge::run_regularize},
    {"synth", "generate a procedural demo city (segmentation, DSM, DTM, true footprints)", lodforge::run_synth},
    {"options", "print every stage option with its default", lodforge::run_options},
};

void usage(std::ostream& out) {
  out << "lodforge " << LODFORGE_VERSION << " — vectorized LOD0/LOD1 building models from segmentation rasters\n\n"
      << "usage: lodforge COMMAND [options]   (lodforge COMMAND --help for its options)\n\ncommands:\n";
  for (const Command& c : commands) out << "  " << c.name << std::string(14 - std::strlen(c.name), ' ') << c.summary << '\n';
}

}  // namespace

int main(int argc, char** argv) {
  // The allocator keeps what the tiles free: buffers up to 32 MB (tile windows, labels, decoded
  // blocks) come from the heap instead of fresh mappings, and up to 64 MB of free heap is kept
  // instead of handed back. glibc's defaults return both to the kernel, and the next tile's first
  // touch of every page faults again: with two threads a third of a run's kernel time
  // (docs/performance.md, item 19). Set before any thread starts.
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
  mallopt(M_TRIM_THRESHOLD, 64 * 1024 * 1024);
  // Logs go to standard error (standard output is for data a command prints); their level from
  // LODFORGE_LOG_LEVEL, then --log-level, -q (warnings and errors) or -v (debug) of any command.
  spdlog::set_default_logger(spdlog::stderr_color_mt("lodforge"));
  spdlog::set_pattern("[%H:%M:%S] [%^%l%$] %v");
  std::string level = std::getenv("LODFORGE_LOG_LEVEL") ? std::getenv("LODFORGE_LOG_LEVEL") : "info";
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-q" || a == "--quiet") level = "warn";
    else if (a == "-v" || a == "--verbose") level = "debug";
    else if (a == "--log-level" && i + 1 < argc) level = argv[i + 1];
    else if (a.rfind("--log-level=", 0) == 0) level = a.substr(12);
    else if (a == "--config" && i + 2 < argc) CPLSetConfigOption(argv[i + 1], argv[i + 2]);  // as GDAL's utilities
  }
  static const std::vector<std::string> levels{"trace", "debug", "info", "warn", "error"};
  if (std::find(levels.begin(), levels.end(), level) == levels.end()) {
    std::cerr << "lodforge: usage error: log level '" << level << "': must be one of trace, debug, info, warn, error\n";
    return 2;
  }
  spdlog::set_level(spdlog::level::from_str(level));
  GDALAllRegister();  // once, before any worker thread opens a dataset
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    usage(argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version") || !std::strcmp(argv[1], "version")) {
    std::cout << "lodforge " << LODFORGE_VERSION << " (git " << LODFORGE_GIT_REVISION << ")\n"
              << "GDAL " << GDALVersionInfo("RELEASE_NAME") << ", CGAL " << CGAL_VERSION_STR << ", TBB " << TBB_VERSION_MAJOR << "."
              << TBB_VERSION_MINOR << ", OpenCV " << CV_VERSION << ", Ceres " << CERES_VERSION_STRING << ", spdlog " << SPDLOG_VER_MAJOR
              << "." << SPDLOG_VER_MINOR << "." << SPDLOG_VER_PATCH << ", Eigen " << EIGEN_WORLD_VERSION << "." << EIGEN_MAJOR_VERSION
              << "." << EIGEN_MINOR_VERSION << '\n';
    return 0;
  }
  for (const Command& c : commands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    try {
      return c.run(argc, argv);
    } catch (const lodforge::UsageError& e) {
      std::cerr << "lodforge " << c.name << ": usage error: " << e.what() << '\n';
      return 2;
    } catch (const lodforge::InputError& e) {
      std::cerr << "lodforge " << c.name << ": error: " << e.what() << '\n';
      return 1;
    } catch (const std::filesystem::filesystem_error& e) {
      // A file or directory lodforge could not create, move or remove: the machine's state, not a bug.
      std::cerr << "lodforge " << c.name << ": error: " << e.what() << lodforge::disk_full_note(e.path1()) << '\n';
      return 1;
    } catch (const std::bad_alloc&) {
      std::cerr << "lodforge " << c.name << ": error: out of memory; give fewer threads, smaller tiles (tiling.tile_size_m) "
                << "or a smaller tiling.gdal_cache_mb\n";
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "lodforge " << c.name << ": internal error: " << e.what() << '\n';
      return 3;
    }
  }
  // The nearest command, when the name is one or two typos away.
  std::string nearest;
  std::size_t best = 3;
  for (const Command& c : commands) {
    const std::string a = argv[1], b = c.name;
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diagonal = up;
      }
    }
    if (row[b.size()] < best) { best = row[b.size()]; nearest = b; }
  }
  std::cerr << "lodforge: unknown command '" << argv[1] << "'" << (nearest.empty() ? "" : "; did you mean '" + nearest + "'?") << "\n\n";
  usage(std::cerr);
  return 2;
}
