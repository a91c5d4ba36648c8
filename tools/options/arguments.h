#pragma once
// The tools' command line: one parser for every tool, and the errors and exit codes they share.

#include <cstddef>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace fot_tools {

constexpr int kExitOk = 0;
constexpr int kExitUsage = 1;  ///< bad arguments
constexpr int kExitInput = 2;  ///< a file that cannot be read, is not valid, or cannot be written

/** The text with its control characters escaped ("\\n", "\\x1b"): an error message stays on one line. */
std::string printable(const std::string& text);

/** A one-line message for the user; the tool prints it and exits with `code`. */
struct ToolError : std::runtime_error {
  ToolError(int exit_code, const std::string& what) : std::runtime_error(what), code(exit_code) {}
  int code;
};

/**
 * A tool's command line, parsed once: options with a value, switches, and positional arguments. It refuses
 * (ToolError, exit code kExitUsage) an unknown option, an option given twice, a missing or empty value, and
 * fewer or more positional arguments than the tool takes; with -h or --help only the help is asked for.
 * Values are checked when read: a number must be the whole value and finite, at the precision it is used in.
 */
class Arguments {
 public:
  static constexpr std::size_t kAny = std::size_t(-1);

  Arguments(int argc, char** argv, std::set<std::string> valued, std::set<std::string> switches,
            std::size_t min_positional = 0, std::size_t max_positional = kAny);

  /** -h or --help: then nothing else was checked. */
  bool helpAsked() const { return help_; }
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  /** The option's value, if given; throws ToolError if it does not parse. */
  bool get(const std::string& name, double& value) const;
  /** A value used as a float: finite as a float too. */
  bool get(const std::string& name, float& value) const;
  bool get(const std::string& name, int& value) const;
  bool get(const std::string& name, std::string& value) const;
  /** Comma-separated numbers, exactly `count` of them, each finite as a double (or as a float if as_float).
   */
  bool get(const std::string& name, std::vector<double>& values, std::size_t count,
           bool as_float = false) const;
  /** A positive, finite value, if given. */
  bool getPositive(const std::string& name, double& value) const;
  /** -res, if given: a resolution CellGrid accepts, with cell centres that are floats. */
  bool getResolution(double& value) const;
  const std::vector<std::string>& positional() const { return positional_; }

 private:
  std::map<std::string, std::string> values_;  // switches map to ""
  std::vector<std::string> positional_;
  bool help_ = false;
};

}  // namespace fot_tools
