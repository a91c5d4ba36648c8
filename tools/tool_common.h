#pragma once
// What the command-line tools share: PCL-style option checks, inputs by file extension, exit codes.

#include <new>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <pcl/console/parse.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace fot_tools {

constexpr int kExitOk = 0;
constexpr int kExitUsage = 1;  ///< bad arguments
constexpr int kExitInput = 2;  ///< a file that cannot be read, is not valid, or cannot be written

/** A one-line message for the user; the tool prints it and exits with `code`. */
struct ToolError : std::runtime_error {
  ToolError(int exit_code, const std::string& what) : std::runtime_error(what), code(exit_code) {}
  int code;
};

/**
 * The command line, checked the way PCL's tools read it (pcl::console): options with a value, switches,
 * and the rest positional. Unknown options, missing values and unparsable numbers throw ToolError.
 */
class Arguments {
 public:
  Arguments(int argc, char** argv, std::set<std::string> valued, std::set<std::string> switches);

  bool has(const std::string& name) const { return pcl::console::find_switch(argc_, argv_, name.c_str()); }
  /** The option's value, if given; throws ToolError if it does not parse. */
  bool get(const std::string& name, double& value) const;
  bool get(const std::string& name, int& value) const;
  bool get(const std::string& name, std::string& value) const;
  /** Comma-separated numbers, exactly `count` of them. */
  bool get(const std::string& name, std::vector<double>& values, std::size_t count) const;
  /** A positive, finite value, if given. */
  bool getPositive(const std::string& name, double& value) const;
  /** -res, if given: a resolution CellGrid accepts, with cell centres that are floats. */
  bool getResolution(double& value) const;
  const std::vector<std::string>& positional() const { return positional_; }

 private:
  int argc_;
  char** argv_;
  std::vector<std::string> positional_;
};

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

/** Reads a .fot, .bt or .ot map. */
pcl::fot::FastOctTree loadMap(const std::string& path);

/** True for the extensions loadMap reads. */
bool isMapFile(const std::string& path);

/** Runs a tool's body: prints a ToolError or any other exception as one line, and returns the exit code. */
template <typename Body>
int runTool(const char* tool, Body&& body) {
  try {
    return body();
  } catch (const ToolError& e) {
    pcl::console::print_error("%s: %s\n", tool, e.what());
    return e.code;
  } catch (const std::bad_alloc&) {
    pcl::console::print_error("%s: out of memory\n", tool);
    return kExitInput;
  } catch (const std::exception& e) {
    pcl::console::print_error("%s: %s\n", tool, e.what());
    return kExitInput;
  }
}

}  // namespace fot_tools
