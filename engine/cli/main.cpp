// lodforge: one binary, subcommands registered in one explicit list.
#include <cstring>
#include <filesystem>
#include <new>
#include <malloc.h>
#include <iostream>
#include <gdal_priv.h>
#include <spdlog/spdlog.h>

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
  spdlog::set_pattern("[%H:%M:%S] [%^%l%$] %v");
  GDALAllRegister();  // once, before any worker thread opens a dataset
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "help")) {
    usage(argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::cout << "lodforge " << LODFORGE_VERSION << '\n';
    return 0;
  }
  for (const Command& c : commands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    try {
      return c.run(argc, argv);
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
  std::cerr << "lodforge: unknown command '" << argv[1] << "'\n\n";
  usage(std::cerr);
  return 2;
}
