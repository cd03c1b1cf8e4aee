#include "core/io/output_files.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>

#include "core/io/csv.h"

namespace photopose {
namespace {

namespace fs = std::filesystem;

// Temporary names keep at most this many bytes of the target's name, so that they stay below
// NAME_MAX (255) with the ".photopose-<pid>-XXXXXX" part.
constexpr size_t kMaxNameInTemporary = 200;
// Symlinks followed at most (the kernel's own limit is 40).
constexpr int kMaxSymlinkHops = 40;

std::string Named(const std::string& label, const std::string& path) {
  return EscapeForMessage(label.empty() ? path : label + "=" + path);
}

std::string SystemError(int error_number) { return std::strerror(error_number); }

// The folder part of a path ("." for a bare name) and its last component.
std::string FolderOf(const std::string& path) {
  const std::string folder = fs::path(path).parent_path().string();
  return folder.empty() ? "." : folder;
}
std::string NameOf(const std::string& path) { return fs::path(path).filename().string(); }

// Follows the symlink chain of `path` to the node it finally names, which may not exist.
bool FollowSymlinks(const std::string& path, std::string* final_path, int* error_number) {
  std::string current = path;
  for (int hop = 0; hop < kMaxSymlinkHops; ++hop) {
    struct stat info;
    if (lstat(current.c_str(), &info) != 0 || !S_ISLNK(info.st_mode)) {
      *final_path = current;
      return true;
    }
    std::string target(PATH_MAX, '\0');
    const ssize_t length = readlink(current.c_str(), target.data(), target.size());
    if (length < 0) {
      *error_number = errno;
      return false;
    }
    target.resize(static_cast<size_t>(length));
    current = target.front() == '/' ? target : FolderOf(current) + "/" + target;
  }
  *error_number = ELOOP;
  return false;
}

bool RealPath(const std::string& path, std::string* real) {
  char buffer[PATH_MAX];
  if (realpath(path.c_str(), buffer) == nullptr) return false;
  *real = buffer;
  return true;
}

// The descriptor a path names directly: /dev/stdin, /dev/stdout, /dev/stderr, /dev/fd/N,
// /proc/self/fd/N; -1 otherwise.
int DescriptorOf(const std::string& path) {
  if (path == "/dev/stdin") return 0;
  if (path == "/dev/stdout") return 1;
  if (path == "/dev/stderr") return 2;
  for (const std::string prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    if (path.rfind(prefix, 0) != 0 || path.size() == prefix.size() ||
        path.size() > prefix.size() + 6)
      continue;
    int fd = 0;
    for (size_t i = prefix.size(); i < path.size(); ++i) {
      if (path[i] < '0' || path[i] > '9') return -1;
      fd = fd * 10 + (path[i] - '0');
    }
    return fd;
  }
  return -1;
}

mode_t CurrentUmask() {
  const mode_t mask = umask(0);
  umask(mask);
  return mask;
}

// The mode a file written at `target` gets: the replaced file's, else rw-rw-rw- less the umask.
mode_t ModeFor(const std::string& target, mode_t fresh) {
  struct stat info;
  if (stat(target.c_str(), &info) == 0) return info.st_mode & 07777;
  return fresh & ~CurrentUmask();
}

bool WriteAll(int fd, std::string_view contents, int* error_number) {
  const char* data = contents.data();
  size_t left = contents.size();
  while (left > 0) {
    const ssize_t written = write(fd, data, left);
    if (written < 0) {
      if (errno == EINTR) continue;
      *error_number = errno;
      return false;
    }
    data += written;
    left -= static_cast<size_t>(written);
  }
  return true;
}

void SyncFolder(const std::string& folder) {
  const int fd = open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  fsync(fd);
  close(fd);
}

// The prefix of every temporary that stands for `target`: ".<name>.photopose-".
std::string TemporaryPrefix(const std::string& target) {
  return "." + NameOf(target).substr(0, kMaxNameInTemporary) + ".photopose-";
}

std::string TemporaryPattern(const std::string& target) {
  return FolderOf(target) + "/" + TemporaryPrefix(target) + std::to_string(getpid()) + "-XXXXXX";
}

// Removes the temporaries that runs which no longer exist left for `target` (files or folders
// named ".<name>.photopose-<pid>-..."; also ".<temporary>.photopose-..." of nested writes).
void RemoveStaleTemporaries(const std::string& target) {
  const std::string folder = FolderOf(target);
  std::string name = NameOf(target).substr(0, kMaxNameInTemporary);
  name.erase(0, name.find_first_not_of('.'));
  const std::string prefix = name + ".photopose-";
  DIR* dir = opendir(folder.c_str());
  if (dir == nullptr) return;
  std::vector<std::string> stale;
  while (const dirent* entry = readdir(dir)) {
    std::string_view entry_name = entry->d_name;
    if (entry_name.empty() || entry_name.front() != '.') continue;
    entry_name.remove_prefix(std::min(entry_name.find_first_not_of('.'), entry_name.size()));
    if (entry_name.substr(0, prefix.size()) != prefix) continue;
    const std::string_view rest = entry_name.substr(prefix.size());
    const size_t dash = rest.find('-');
    if (dash == 0 || dash == std::string_view::npos || dash > 9) continue;
    long pid = 0;
    bool digits = true;
    for (size_t i = 0; i < dash; ++i) {
      digits = digits && rest[i] >= '0' && rest[i] <= '9';
      pid = pid * 10 + (rest[i] - '0');
    }
    if (!digits || pid <= 0 || pid == getpid()) continue;
    if (kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)
      stale.push_back(folder + "/" + entry->d_name);
  }
  closedir(dir);
  for (const std::string& path : stale) {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
}

// Whether two paths name the same existing file (same device and inode).
bool SameInode(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  return stat(a.c_str(), &sa) == 0 && stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

// The canonical path of an input (after symlinks), or the path itself when it does not resolve.
std::string CanonicalInput(const std::string& path) {
  std::string real;
  return RealPath(path, &real) ? real : path;
}

}  // namespace

// ------------------------------------------------------------------ OutputFiles

OutputFiles::~OutputFiles() {
  if (!committed_) Abort();
}

Status OutputFiles::AddInput(const std::string& label, const std::string& path) {
  if (path.empty()) return Status::Ok();
  if (path == "-") {
    if (!standard_input_label_.empty()) {
      return Status::Error(Named(label, path) + ": standard input is already read as " +
                           Named(standard_input_label_, path) + "; only one input can be '-'");
    }
    standard_input_label_ = label.empty() ? "-" : label;
    return Status::Ok();
  }
  inputs_.push_back({label, path});
  return Status::Ok();
}

OutputFiles::Output* OutputFiles::Find(const std::string& path) {
  // The first not yet staged: an in-place path such as /dev/null may be given twice.
  for (Output& output : outputs_)
    if (output.path == path && !output.staged) return &output;
  return nullptr;
}

Status OutputFiles::AddOutput(const std::string& label, const std::string& path) {
  const std::string name = Named(label, path);
  if (path.empty()) return Status::Error(name + ": the output path is empty");
  Output output;
  output.label = label;
  output.path = path;
  output.descriptor = DescriptorOf(path);
  struct stat info;
  if (output.descriptor >= 0) {
    output.kind = Kind::kDescriptor;
    if (fstat(output.descriptor, &info) != 0)
      return Status::Error(name + ": descriptor " + std::to_string(output.descriptor) +
                           " is not open");
  } else {
    std::string final_path;
    int error_number = 0;
    if (!FollowSymlinks(path, &final_path, &error_number))
      return Status::Error(name + ": cannot follow the symlink: " + SystemError(error_number));
    const std::string file_name = NameOf(final_path);
    if (stat(final_path.c_str(), &info) == 0) {
      if (S_ISDIR(info.st_mode)) return Status::Error(name + ": is a folder, not a file");
      if (S_ISREG(info.st_mode)) {
        output.kind = Kind::kReplace;
        RealPath(final_path, &output.target);
      } else {
        output.kind = Kind::kInPlace;
        output.target = final_path;
      }
    } else if (errno != ENOENT) {
      return Status::Error(name + ": cannot check: " + SystemError(errno));
    } else if (file_name.empty() || file_name == "." || file_name == "..") {
      return Status::Error(name + ": names a folder, not a file");
    } else {
      std::string folder;
      if (!RealPath(FolderOf(final_path), &folder) || stat(folder.c_str(), &info) != 0 ||
          !S_ISDIR(info.st_mode)) {
        return Status::Error(name + ": the folder '" + EscapeForMessage(FolderOf(final_path)) +
                             "' does not exist");
      }
      output.kind = Kind::kReplace;
      output.target = (folder == "/" ? "" : folder) + "/" + file_name;
    }
    if (output.kind == Kind::kReplace &&
        access(FolderOf(output.target).c_str(), W_OK | X_OK) != 0) {
      return Status::Error(name + ": cannot write in the folder '" +
                           EscapeForMessage(FolderOf(output.target)) + "': " + SystemError(errno));
    }
  }

  const std::string node = output.kind == Kind::kDescriptor
                               ? "/proc/self/fd/" + std::to_string(output.descriptor)
                               : output.target;
  for (const Input& input : inputs_) {
    if (CanonicalInput(input.path) == output.target || SameInode(input.path, node)) {
      return Status::Error(name + " is the input " + Named(input.label, input.path) +
                           "; photopose never writes over an input: choose another output file");
    }
  }
  if (output.kind == Kind::kReplace) {
    for (const Output& other : outputs_) {
      if (other.kind == Kind::kReplace &&
          (other.target == output.target || SameInode(other.target, output.target))) {
        return Status::Error(name + " is the same file as " + Named(other.label, other.path) +
                             "; every output needs a file of its own");
      }
    }
    RemoveStaleTemporaries(output.target);
  }
  outputs_.push_back(std::move(output));
  return Status::Ok();
}

Status OutputFiles::StageFailed(Status status) {
  Abort();
  return status;
}

Status TextPieces::WriteToFile(std::string_view bytes) const {
  int error_number = 0;
  if (!WriteAll(fd_, bytes, &error_number))
    return Status::Error(name_ + ": cannot write: " + SystemError(error_number));
  return Status::Ok();
}

Status TextPieces::Flush() {
  if (fd_ < 0 || text_.empty()) return Status::Ok();
  PHOTOPOSE_RETURN_IF_ERROR(WriteToFile(text_));
  text_.clear();
  return Status::Ok();
}

Status TextPieces::Write(std::string_view contents) {
  if (fd_ < 0) {
    text_.append(contents);
    return Status::Ok();
  }
  PHOTOPOSE_RETURN_IF_ERROR(Flush());
  return WriteToFile(contents);
}

Status OutputFiles::Stage(const std::string& path, std::string_view contents) {
  return StageInPieces(path, [&](TextPieces* out) { return out->Write(contents); });
}

Status OutputFiles::StageInPieces(const std::string& path,
                                  const std::function<Status(TextPieces* out)>& format) {
  if (Find(path) == nullptr) PHOTOPOSE_RETURN_IF_ERROR(AddOutput("", path));
  Output* output = Find(path);
  const std::string name = Named(output->label, output->path);
  TextPieces pieces;
  if (output->kind != Kind::kReplace) {
    const Status formatted = format(&pieces);
    if (!formatted.ok()) return StageFailed(formatted);
    output->contents = std::move(pieces.text_);
    output->staged = true;
    return Status::Ok();
  }
  std::string temporary = TemporaryPattern(output->target);
  const int fd = mkstemp(temporary.data());
  if (fd < 0) {
    return StageFailed(
        Status::Error(name + ": cannot create a temporary file: " + SystemError(errno)));
  }
  output->temporary = temporary;
  Status written = Status::Ok();
  if (fchmod(fd, ModeFor(output->target, 0666)) != 0) {
    written = Status::Error(name + ": cannot set permissions: " + SystemError(errno));
  } else {
    pieces.fd_ = fd;
    pieces.name_ = name;
    written = format(&pieces);
    if (written.ok()) written = pieces.Flush();
    if (written.ok() && fsync(fd) != 0)
      written = Status::Error(name + ": cannot write: " + SystemError(errno));
  }
  if (close(fd) != 0 && written.ok())
    written = Status::Error(name + ": cannot write: " + SystemError(errno));
  if (!written.ok()) return StageFailed(written);
  output->staged = true;
  return Status::Ok();
}

Status OutputFiles::StageWith(
    const std::string& path,
    const std::function<Status(const std::string& temporary_path)>& write) {
  if (Find(path) == nullptr) PHOTOPOSE_RETURN_IF_ERROR(AddOutput("", path));
  Output* output = Find(path);
  const std::string name = Named(output->label, output->path);
  // A temporary beside the target, or in the temporary folder for an in-place target.
  std::string temporary = output->kind == Kind::kReplace
                              ? TemporaryPattern(output->target)
                              : (fs::temp_directory_path() / ".photopose-XXXXXX").string();
  const int fd = mkstemp(temporary.data());
  if (fd < 0) {
    return StageFailed(
        Status::Error(name + ": cannot create a temporary file: " + SystemError(errno)));
  }
  close(fd);
  Status written = write(temporary);
  if (!written.ok()) {
    unlink(temporary.c_str());
    std::string message = written.message();
    const std::string escaped = EscapeForMessage(temporary);
    const std::string replacement = EscapeForMessage(output->path);
    for (size_t at = message.find(escaped); at != std::string::npos;
         at = message.find(escaped, at + replacement.size())) {
      message.replace(at, escaped.size(), replacement);
    }
    return StageFailed(Status::Error(message));
  }
  if (output->kind == Kind::kReplace) {
    output->temporary = temporary;
    if (chmod(temporary.c_str(), ModeFor(output->target, 0666)) != 0) {
      return StageFailed(Status::Error(name + ": cannot set permissions: " + SystemError(errno)));
    }
  } else {
    std::string contents;
    const Status read = ReadTextFile(temporary, &contents);
    unlink(temporary.c_str());
    if (!read.ok()) return StageFailed(read);
    output->contents = std::move(contents);
  }
  output->staged = true;
  return Status::Ok();
}

Status OutputFiles::Commit() {
  for (const Output& output : outputs_) {
    if (!output.staged) {
      Abort();
      return Status::Error(Named(output.label, output.path) + ": nothing was written for it");
    }
  }
  // In-place outputs first: they cannot be undone, the renames can still be skipped.
  for (const Output& output : outputs_) {
    if (output.kind == Kind::kReplace) continue;
    const std::string name = Named(output.label, output.path);
    int error_number = 0;
    if (output.kind == Kind::kDescriptor) {
      std::fflush(nullptr);  // what the process printed comes first
      if (!WriteAll(output.descriptor, output.contents, &error_number)) {
        Abort();
        return Status::Error(name + ": cannot write: " + SystemError(error_number));
      }
      continue;
    }
    // O_NONBLOCK: a FIFO without a reader fails (ENXIO) instead of waiting for one.
    const int fd = open(output.target.c_str(), O_WRONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) {
      error_number = errno;
      Abort();
      if (error_number == ENXIO) return Status::Error(name + ": no process is reading the FIFO");
      return Status::Error(name + ": cannot open: " + SystemError(error_number));
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    const bool ok = WriteAll(fd, output.contents, &error_number);
    close(fd);
    if (!ok) {
      Abort();
      return Status::Error(name + ": cannot write: " + SystemError(error_number));
    }
  }
  std::set<std::string> folders;
  for (Output& output : outputs_) {
    if (output.kind != Kind::kReplace) continue;
    if (rename(output.temporary.c_str(), output.target.c_str()) != 0) {
      const int error_number = errno;
      Abort();
      return Status::Error(Named(output.label, output.path) +
                           ": cannot replace: " + SystemError(error_number));
    }
    output.temporary.clear();
    folders.insert(FolderOf(output.target));
  }
  for (const std::string& folder : folders) SyncFolder(folder);
  committed_ = true;
  return Status::Ok();
}

void OutputFiles::Abort() {
  for (Output& output : outputs_) {
    if (!output.temporary.empty()) unlink(output.temporary.c_str());
    output.temporary.clear();
    output.contents.clear();
    output.staged = false;
  }
}

Status WriteFileAtomically(const std::string& path, const std::string& contents) {
  OutputFiles outputs;
  PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", path));
  PHOTOPOSE_RETURN_IF_ERROR(outputs.Stage(path, contents));
  return outputs.Commit();
}

// ------------------------------------------------------------------ folders

namespace {

// The files and subfolders a dataset puts in its folder, as relative paths.
struct FolderLayout {
  std::set<std::string> files;
  std::set<std::string> folders;
};

FolderLayout LayoutOf(const std::vector<FolderFile>& files) {
  FolderLayout layout;
  for (const FolderFile& file : files) {
    layout.files.insert(file.relative_path);
    for (fs::path parent = fs::path(file.relative_path).parent_path(); !parent.empty();
         parent = parent.parent_path())
      layout.folders.insert(parent.string());
  }
  return layout;
}

const char* KindOf(mode_t mode) {
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "a special file";
}

// Calls visit(path, relative path, lstat of it) for every entry of `folder` (whose own relative
// path is `relative`), stopping at the first error.
template <typename Visit>
Status ForEachEntry(const std::string& name, const std::string& folder, const std::string& relative,
                    Visit visit) {
  DIR* dir = opendir(folder.c_str());
  if (dir == nullptr)
    return Status::Error(name + ": cannot read the folder: " + SystemError(errno));
  Status status;
  while (const dirent* entry = readdir(dir)) {
    const std::string entry_name = entry->d_name;
    if (entry_name == "." || entry_name == "..") continue;
    const std::string path = folder + "/" + entry_name;
    struct stat info;
    if (lstat(path.c_str(), &info) != 0) continue;
    status = visit(path, relative.empty() ? entry_name : relative + "/" + entry_name, info);
    if (!status.ok()) break;
  }
  closedir(dir);
  return status;
}

// Checks that every entry of `folder` (relative path `relative`) can be carried over into a new
// folder: regular files and symlinks anywhere, subfolders only where the layout has one.
Status CheckCarriable(const std::string& name, const std::string& folder,
                      const std::string& relative, const FolderLayout& layout) {
  return ForEachEntry(
      name, folder, relative,
      [&](const std::string& path, const std::string& entry, const struct stat& info) {
        const std::string quoted = "'" + EscapeForMessage(entry) + "'";
        if (S_ISDIR(info.st_mode)) {
          if (layout.folders.count(entry) == 0) {
            return Status::Error(
                name + ": holds the folder " + quoted +
                "; photopose replaces the output folder as a whole and carries over "
                "files only: give a folder of its own to the dataset");
          }
          return CheckCarriable(name, path, entry, layout);
        }
        if (layout.files.count(entry) != 0 && !S_ISREG(info.st_mode))
          return Status::Error(name + ": " + quoted + " is not a regular file");
        if (!S_ISREG(info.st_mode) && !S_ISLNK(info.st_mode)) {
          return Status::Error(name + ": holds " + quoted + ", " + KindOf(info.st_mode) +
                               ", which cannot be carried over into the new folder");
        }
        return Status::Ok();
      });
}

// Copies a regular file (the fall-back when it cannot be hard-linked).
bool CopyFile(const std::string& from, const std::string& to, mode_t mode) {
  std::error_code error;
  return fs::copy_file(from, to, error) && chmod(to.c_str(), mode) == 0;
}

// Mirrors the entries of `from` into `to` (hard links; copies where a link is refused; symlinks
// recreated), leaving out the files of the layout, which are written new.
Status MirrorFolder(const std::string& name, const std::string& from, const std::string& to,
                    const std::string& relative, const FolderLayout& layout) {
  return ForEachEntry(
      name, from, relative,
      [&](const std::string& source, const std::string& entry, const struct stat& info) {
        if (layout.files.count(entry) != 0) return Status::Ok();
        const std::string copy = to + "/" + NameOf(source);
        bool ok = true;
        if (S_ISDIR(info.st_mode)) {
          if (mkdir(copy.c_str(), info.st_mode & 07777) != 0 && errno != EEXIST) {
            ok = false;
          } else {
            PHOTOPOSE_RETURN_IF_ERROR(MirrorFolder(name, source, copy, entry, layout));
          }
        } else if (S_ISLNK(info.st_mode)) {
          std::string target(PATH_MAX, '\0');
          const ssize_t length = readlink(source.c_str(), target.data(), target.size());
          ok = length >= 0;
          if (ok) {
            target.resize(static_cast<size_t>(length));
            ok = symlink(target.c_str(), copy.c_str()) == 0;
          }
        } else {
          ok = link(source.c_str(), copy.c_str()) == 0 ||
               CopyFile(source, copy, info.st_mode & 07777);
        }
        if (ok) return Status::Ok();
        return Status::Error(name + ": cannot carry '" + EscapeForMessage(entry) +
                             "' over into the new folder: " + SystemError(errno));
      });
}

// Where a folder output goes: the folder it names after symlinks, whether it exists.
Status ResolveFolder(const std::string& name, const std::string& folder, std::string* target,
                     bool* exists) {
  std::string final_path;
  int error_number = 0;
  if (!FollowSymlinks(folder, &final_path, &error_number))
    return Status::Error(name + ": cannot follow the symlink: " + SystemError(error_number));
  struct stat info;
  *exists = stat(final_path.c_str(), &info) == 0;
  if (*exists && !S_ISDIR(info.st_mode))
    return Status::Error(name + ": exists and is not a folder");
  if (!*exists && errno != ENOENT)
    return Status::Error(name + ": cannot check: " + SystemError(errno));
  if (*exists) {
    RealPath(final_path, target);
  } else {
    *target = fs::path(final_path).lexically_normal().string();
    while (target->size() > 1 && target->back() == '/') target->pop_back();
  }
  return Status::Ok();
}

}  // namespace

Status CheckOutputFolder(const std::string& label, const std::string& folder,
                         const std::vector<FolderFile>& files) {
  const std::string name = Named(label, folder);
  if (folder.empty()) return Status::Error(name + ": the output folder is empty");
  std::string target;
  bool exists = false;
  PHOTOPOSE_RETURN_IF_ERROR(ResolveFolder(name, folder, &target, &exists));
  if (!exists) return Status::Ok();
  std::string current;
  if (target == "/" ||
      (RealPath(".", &current) && (current == target || current.rfind(target + "/", 0) == 0))) {
    return Status::Error(name +
                         ": is the current folder or contains it; photopose replaces the "
                         "output folder as a whole: give another folder");
  }
  return CheckCarriable(name, target, "", LayoutOf(files));
}

Status WriteFolderAtomically(const std::string& label, const std::string& folder,
                             const std::vector<FolderFile>& files) {
  const std::string name = Named(label, folder);
  PHOTOPOSE_RETURN_IF_ERROR(CheckOutputFolder(label, folder, files));
  std::string target;
  bool exists = false;
  PHOTOPOSE_RETURN_IF_ERROR(ResolveFolder(name, folder, &target, &exists));
  const std::string parent = FolderOf(target);
  std::error_code error;
  fs::create_directories(parent, error);
  if (error) {
    return Status::Error(name + ": cannot create the folder '" + EscapeForMessage(parent) +
                         "': " + error.message());
  }
  RemoveStaleTemporaries(target);

  std::string staging = TemporaryPattern(target);
  if (mkdtemp(staging.data()) == nullptr) {
    return Status::Error(name +
                         ": cannot create a temporary folder beside it: " + SystemError(errno));
  }
  const auto fail = [&staging](Status status) {
    std::error_code ignored;
    fs::remove_all(staging, ignored);
    return status;
  };
  const FolderLayout layout = LayoutOf(files);
  if (exists) {
    const Status mirrored = MirrorFolder(name, target, staging, "", layout);
    if (!mirrored.ok()) return fail(mirrored);
  }
  const mode_t folder_mode = ModeFor(target, 0777);
  std::set<std::string> folders = {staging};
  for (const std::string& sub : layout.folders) {
    const std::string path = staging + "/" + sub;
    if (mkdir(path.c_str(), ModeFor(target + "/" + sub, 0777)) != 0 && errno != EEXIST)
      return fail(Status::Error(name + ": cannot create '" + sub + "': " + SystemError(errno)));
    folders.insert(path);
  }
  for (const FolderFile& file : files) {
    const std::string path = staging + "/" + file.relative_path;
    const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC,
                        ModeFor(target + "/" + file.relative_path, 0666));
    int error_number = errno;
    bool ok = fd >= 0 && WriteAll(fd, file.contents, &error_number);
    if (ok && fsync(fd) != 0) {
      ok = false;
      error_number = errno;
    }
    if (fd >= 0 && close(fd) != 0 && ok) {
      ok = false;
      error_number = errno;
    }
    if (!ok) {
      return fail(Status::Error(name + ": cannot write '" + file.relative_path +
                                "': " + SystemError(error_number)));
    }
  }
  for (const std::string& path : folders) SyncFolder(path);
  if (chmod(staging.c_str(), folder_mode) != 0)
    return fail(Status::Error(name + ": cannot set permissions: " + SystemError(errno)));

  if (exists) {
    // One atomic step: before it the old folder is complete, after it the new one.
    if (renameat2(AT_FDCWD, staging.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) != 0) {
      return fail(Status::Error(name + ": cannot swap the new folder in: " + SystemError(errno)));
    }
    SyncFolder(parent);
    std::error_code ignored;
    fs::remove_all(staging, ignored);  // now the old folder; a leftover is removed next time
  } else if (rename(staging.c_str(), target.c_str()) != 0) {
    return fail(Status::Error(name + ": cannot create: " + SystemError(errno)));
  }
  SyncFolder(parent);
  return Status::Ok();
}

}  // namespace photopose
