#pragma once
// What the command-line tools share: inputs by file extension, output checks, how a tool reports errors.

#include <new>
#include <string>
#include <vector>

#include <pcl/console/print.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <pcl_fot/tree/fast_oct_tree.h>

#include "arguments.h"

namespace fot_tools {

/**
 * Throws ToolError (kExitUsage) if an output is one of the inputs or another output: the same file, by device
 * and inode after following links, however it is spelt. Outputs that do not exist yet are none of them.
 */
void refuseOverwrites(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs);

/** The file's extension, lower case, with the dot: ".pcd". */
std::string extension(const std::string& path);

/**
 * Throws ToolError unless the directory `file` would be written into exists and is writable: checked before
 * the work, so that a mistyped output path does not lose it.
 */
void requireWritableDirectory(const std::string& file);

/**
 * Throws ToolError (exit 2) naming `what` unless `path` is a regular file: a device may never end, and
 * opening a FIFO would wait for a writer.
 */
void requireRegularFile(const std::string& path, const std::string& what);

/**
 * The next line of a text file, without its end. False at the end of the input, and for a line longer than
 * max_chars, which no file the tools read holds (then the stream is not at its end).
 */
bool readLine(std::istream& in, std::string& line, std::size_t max_chars);

/**
 * -max_memory, in bytes: the most a map may take in memory, as MiB (1024 by default). A file whose map would
 * need more, say a few bytes of OctoMap cube placed off its grid, is refused at once with the size it needs.
 */
std::size_t maxMemory(const Arguments& args);

/** Reads a .fot, .bt or .ot map, or a tile set (tile_set.h), of at most max_bytes. */
pcl::fot::FastOctTree loadMap(const std::string& path, std::size_t max_bytes);

/** True for what loadMap reads: its extensions and tile sets. */
bool isMapFile(const std::string& path);

/**
 * Runs a tool's body: prints a ToolError or any other exception as one line, a usage error with the tool's
 * `syntax` ("fot_psi a b [options]"), and returns the exit code.
 */
template <typename Body>
int runTool(const char* tool, const char* syntax, Body&& body) {
  try {
    return body();
  } catch (const ToolError& e) {
    if (e.code == kExitUsage)
      pcl::console::print_error("%s: %s (usage: %s; -h for help)\n", tool, printable(e.what()).c_str(),
                                syntax);
    else
      pcl::console::print_error("%s: %s\n", tool, printable(e.what()).c_str());
    return e.code;
  } catch (const pcl::fot::MemoryLimitError& e) {
    pcl::console::print_error("%s: %s (-max_memory raises the cap, where the tool has it)\n", tool,
                              printable(e.what()).c_str());
    return kExitInput;
  } catch (const std::bad_alloc&) {
    pcl::console::print_error("%s: out of memory\n", tool);
    return kExitInput;
  } catch (const std::exception& e) {
    pcl::console::print_error("%s: %s\n", tool, printable(e.what()).c_str());
    return kExitInput;
  }
}

}  // namespace fot_tools
