// Checks shared by the subcommands, all made before any work:
//  - option values: CLI11 validators, so that a bad value is a usage error (exit 2) whose message names the
//    option ("--near: must be a finite number > 0 (got '0')");
//  - output paths: the folder exists and is writable, checked up front without creating or truncating the
//    final file (bad input: exit 1);
//  - text from assets or the command line printed to a terminal: control characters escaped (printable).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "visbuf/core/result.h"

namespace visbuf::tools {

// `text` safe to print to a terminal: every control character -- C0 (0x00-0x1f, so ESC, newline, tab), DEL
// (0x7f), C1 (U+0080-U+009F, and any stray byte 0x80-0xff that is not part of valid UTF-8, which an 8-bit
// terminal may take for C1), and the Unicode line / paragraph separators and bidirectional overrides --
// is written as \xNN, one escape per byte. Everything else, valid UTF-8 included, is unchanged, and so is
// a backslash (so that escaping twice changes nothing). With keepNewlines, '\n' is kept (multi-line
// messages made by this program, such as the device selection report).
std::string printable(std::string_view text, bool keepNewlines = false);
// The same, for printf's "%s".
inline std::string printable(const char* text) { return printable(std::string_view(text ? text : "")); }

// ---- option validators -----------------------------------------------------------------------------------
// Each checks the text as typed (before CLI11 converts it), so "nan", "inf", "1e999", "-1" for an unsigned
// option, "010" (octal to strtoull) and "5abc" are all rejected with the accepted range in the message.

// A finite decimal number in [lo, hi]; loOpen / hiOpen make that end exclusive. lo = -inf / hi = +inf: no bound.
CLI::Validator finiteNumber(double lo = -std::numeric_limits<double>::infinity(),
                            double hi = std::numeric_limits<double>::infinity(), bool loOpen = false,
                            bool hiOpen = false);
// A plain decimal integer (digits, an optional sign) in [lo, hi].
CLI::Validator integerIn(int64_t lo, int64_t hi);
CLI::Validator unsignedIn(uint64_t lo, uint64_t hi);
// "WxH", each 1..16384 (parseSize).
CLI::Validator imageSize();
// A power of two in 1..max.
CLI::Validator powerOfTwo(uint32_t max);
// A path (file or folder, to read or write): not empty ("--scene: empty path"; a usage error, not "file not found"
// about a blank name).
CLI::Validator nonEmptyPath();

// ---- paths (bad input, exit 1) -----------------------------------------------------------------------------
// A file that will be written atomically (temporary file in the same folder, then rename): `path` names a
// file (not a folder, not a FIFO or device), and its folder exists, is a folder, and is writable. Nothing is
// created. `option` names the option in the message ("-o", "--json").
Status checkOutputFile(const std::string& option, const std::string& path);
// An output folder (created when missing): an existing folder must be writable; a missing one must have a
// writable folder as its nearest existing ancestor. Nothing is created.
Status checkOutputFolder(const std::string& option, const std::string& path);

// ---- no output over an input, no two outputs in one file ------------------------------------------------
// Every file a command writes, by the option that names it. inFolder: one of the fixed files an output folder
// gets (bench.json in bench's -o folder): its folder is checked by checkOutputFolder, not here.
struct OutputFile {
  std::string option;
  std::string path;
  bool inFolder = false;
};
// Called before any work with the inputs named on the command line noted (core/file_read.h: noteInputFile), and
// again once the inputs are loaded (the glTF's buffers and images, packs, --mesh files: everything the loaders
// read or the asset references is then in the input log). Each output: checkOutputFile (unless inFolder); not
// an input of this command: the same file, a hard link or a symbolic link to one ("-o 'scene.bin': is an input
// of this command (scene.gltf: buffer 0); refused"); and not the same file as another output (the same path
// once resolved, or the same existing file through a link): "--json 'x.png': is also -o". Bad input (exit 1).
// commitFile() refuses the same again at the moment of writing, for an output a command would forget to list.
Status checkOutputs(const std::vector<OutputFile>& outputs);

// ---- memory ----------------------------------------------------------------------------------------------
// What this process can still allocate: MemAvailable of /proc/meminfo (else physical pages x page size),
// capped by RLIMIT_AS less the address space already mapped and by RLIMIT_DATA. `source` says which bound won.
uint64_t availableHostMemory(std::string* source = nullptr);
// "12.3 GiB", "456.0 MiB", "789 bytes".
std::string formatBytes(uint64_t bytes);

}  // namespace visbuf::tools
