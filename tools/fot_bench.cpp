// fot_bench: reruns the paper's experiments on the real scans and writes doc/benchmarks.md.
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/console/time.h>

#include <pcl_fot/io/file_io.h>

#include "bench/sections.h"
#include "tool_common.h"

using namespace pcl::console;
using namespace fot_tools;

namespace {

void printHelp(const char* prog) {
  print_info(
      "Reruns the FastOctTree paper's experiments on real scans, side by side with the baselines,\n"
      "and writes the tables as Markdown.\n\n"
      "Syntax: %s [options]\n\n"
      "  -data <dir>        directory with the scans of PCL's data repository (default: ../shared/data)\n"
      "  -out <file>        Markdown report to write (default: doc/benchmarks.md); the psi plot goes beside "
      "it,\n"
      "                     the other plots (gnuplot) into img/ beside it\n"
      "  -repeats <n>       insertions per cloud and structure (default: 20, as in the paper)\n"
      "  -ray_repeats <n>   rounds of the ray tracing, search, octree, algorithm and psi timings (default: "
      "5)\n"
      "  -dmap_repeats <n>  runs of dmap_v at 1024^3 per scan pair, about 10 s each (default: 3)\n"
      "  -sections <list>   comma-separated subset of: cells,rays,mapping,search,octree,algorithms,psi "
      "(default: "
      "all)\n"
      "  -h                 this help\n\n"
      "Exit codes: 0 done, 1 bad arguments, 2 missing scans or a report that cannot be written.\n",
      prog);
}

/** The -sections list: known names, each at most once, at least one. */
std::set<std::string> sectionList(const std::string& text) {
  const std::set<std::string> known{"cells", "rays", "mapping", "search", "octree", "algorithms", "psi"};
  std::set<std::string> chosen;
  std::stringstream in(text);
  for (std::string name; std::getline(in, name, ',');) {
    if (!known.count(name))
      throw ToolError(kExitUsage, "option -sections: '" + name +
                                      "' is none of cells,rays,mapping,search,octree,algorithms,psi");
    if (!chosen.insert(name).second)
      throw ToolError(kExitUsage, "option -sections names '" + name + "' twice");
  }
  if (chosen.empty() || text.back() == ',')
    throw ToolError(kExitUsage, "option -sections: an empty section name");
  return chosen;
}

std::string firstLineOf(const char* path, const char* key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

/** Draws the report's plots into <its directory>/img/ with scripts/make_pictures.sh, the script behind every
 *  picture of the docs, which can redraw them from the report alone. */
void drawPlots(const std::string& report, const std::string& doc_dir) {
  // __FILE__ names this file as the build gave it, <source tree>/tools/fot_bench.cpp.
  const std::string self = __FILE__,
                    script = self.substr(0, self.rfind("tools/")) + "scripts/make_pictures.sh";
  auto quoted = [](std::string s) {  // for the shell: 'it'\''s'
    for (std::size_t at = s.find('\''); at != std::string::npos; at = s.find('\'', at + 4))
      s.replace(at, 1, "'\\''");
    return "'" + s + "'";
  };
  const std::string command =
      "bash " + quoted(script) + " plots --bench " + quoted(report) + " " + quoted(doc_dir + "/img");
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0)
    print_info("No gnuplot, so no plots: install gnuplot-nox, then run %s\n", command.c_str());
  else if (std::system(command.c_str()) != 0)
    print_warn("The plots failed (%s); the report stands\n", command.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  return runTool("fot_bench", "fot_bench [options]", [&] {
    const Arguments args(argc, argv,
                         {"-data", "-out", "-repeats", "-ray_repeats", "-dmap_repeats", "-sections"},
                         {"-h", "--help"}, 0, 0);
    if (args.helpAsked()) {
      printHelp("fot_bench");
      return kExitOk;
    }
    std::string data_dir = "../shared/data", out = "doc/benchmarks.md",
                sections = "cells,rays,mapping,search,octree,algorithms,psi";
    int repeats = 20, ray_repeats = 5, dmap_repeats = 3;
    args.get("-data", data_dir);
    args.get("-out", out);
    args.get("-repeats", repeats);
    args.get("-ray_repeats", ray_repeats);
    args.get("-dmap_repeats", dmap_repeats);
    args.get("-sections", sections);
    if (repeats < 1 || ray_repeats < 1 || dmap_repeats < 1)
      throw ToolError(kExitUsage, "-repeats, -ray_repeats and -dmap_repeats must be at least 1");
    const std::set<std::string> chosen = sectionList(sections);
    auto wanted = [&](const std::string& s) { return chosen.count(s) != 0; };
    requireWritableDirectory(out);
    const std::string doc_dir = out.find('/') == std::string::npos ? "." : out.substr(0, out.rfind('/'));
    const std::string plot = doc_dir + "/psi_random_maps.png";
    refuseOverwrites(fot_bench::benchScanFiles(data_dir),
                     {out, plot, plot + ".dat", plot + ".gp", plot + ".tmp"});
    TicToc total;
    total.tic();
    const auto scans = fot_bench::loadBenchScans(data_dir);
    std::ostringstream md;
    const std::time_t now = std::time(nullptr);
    char date[32];
    std::strftime(date, sizeof(date), "%Y-%m-%d", std::gmtime(&now));
    md << "# pcl_fot benchmarks\n\n"
       << "Written by `fot_bench` (`tools/fot_bench.cpp`); rerun it with `build/tools/fot_bench -data "
          "<scans> -out doc/benchmarks.md`. Every table comes from one run, "
       << date << ", on " << firstLineOf("/proc/cpuinfo", "model name") << " ("
       << std::thread::hardware_concurrency()
       << " hardware threads), shared with other work: the figures are medians, and the ratios compare "
          "structures measured side by side in the same run. Release build, g++ "
       << __VERSION__ << ".\n\n"
       << "Scans (PCL's data repository): the Kinect frames at 1 cm, the room scans at 5 cm, the terrain "
          "sample at 0.30 m around its own centre, so that each fits the paper's 1024³ grid.\n\n";
    if (wanted("cells")) md << fot_bench::benchCellAccess(scans, repeats) << "\n";
    if (wanted("rays")) md << fot_bench::benchRayTracing(scans, ray_repeats) << "\n";
    if (wanted("mapping")) md << fot_bench::benchMultiScan(scans, ray_repeats) << "\n";
    if (wanted("search"))
      md << fot_bench::benchSearch(scans, ray_repeats) << "\n"
         << fot_bench::benchSearchAgainstNanoflann(scans, data_dir, ray_repeats) << "\n";
    if (wanted("octree")) md << fot_bench::benchOctreeFamily(scans, ray_repeats) << "\n";
    if (wanted("algorithms")) md << fot_bench::benchPclAlgorithms(scans, ray_repeats) << "\n";
    if (wanted("psi")) md << fot_bench::benchPsi(scans, ray_repeats, dmap_repeats, plot) << "\n";
    pcl::fot::io::writeFileAtomically(out, md.str());
    print_info("Wrote %s in %.1f s\n", out.c_str(), total.toc() / 1000.0);
    drawPlots(out, doc_dir);
    return kExitOk;
  });
}
