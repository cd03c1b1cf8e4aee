#pragma once
// Character devices for tests that write to a device (/dev/null, /dev/full).
//
// As root a broken build under test could rename a regular file over the system's /dev/null (the
// very bug these tests catch): root gets a private node made in the test's folder instead. A
// user cannot replace /dev/null, so the system's node is used. Empty when root cannot make a node
// that works (no CAP_MKNOD, a folder mounted nodev): the test then skips that part.
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <string>

namespace photopose::testing {

// `name` is "null" (1, 3) or "full" (1, 7).
inline std::string TestDevice(const std::string& dir, const std::string& name) {
  if (geteuid() != 0) return "/dev/" + name;
  const unsigned minor = name == "full" ? 7 : 3;
  const std::string path = dir + "/" + name;
  unlink(path.c_str());
  if (mknod(path.c_str(), S_IFCHR | 0666, makedev(1, minor)) != 0) return "";
  const int fd = open(path.c_str(), O_WRONLY);
  if (fd < 0) {
    unlink(path.c_str());
    return "";
  }
  close(fd);
  return path;
}

// Whether /dev/stdout may be named as an output: not as root, where a broken build could replace
// the system's symlink (/dev/fd/1, in a file system no one can write, is always safe).
inline bool MayWriteDevStdout() { return geteuid() != 0; }

}  // namespace photopose::testing
