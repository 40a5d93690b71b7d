// The version of this build of visbuf: one project version (CMakeLists.txt, `project(VERSION)`) and
// the git revision of the tree it was built from, when it was built from a git checkout.
#pragma once

#include <string>

namespace visbuf {

// "MAJOR.MINOR.PATCH", e.g. "0.2.0".
const char* versionNumber();
// `git describe --always --dirty` of the source tree ("" when it was not a git checkout).
const char* gitRevision();

// "0.2.0 (bd0f732c1a2e-dirty)" or "0.2.0": the one string --version prints and every JSON records.
inline std::string versionString() {
  const std::string revision = gitRevision();
  return revision.empty() ? std::string(versionNumber()) : std::string(versionNumber()) + " (" + revision + ")";
}

}  // namespace visbuf
