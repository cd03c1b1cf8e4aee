#pragma once
// The outputs of a run as one transaction: every output is written completely, or none is
// touched (docs/formats.md, "How files are written").
//
//   OutputFiles outputs;
//   PHOTOPOSE_RETURN_IF_ERROR(outputs.AddInput("--points", points_path));  // before any work:
//   PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("--out", out_path));    // the pre-flight check
//   ... read, solve ...
//   PHOTOPOSE_RETURN_IF_ERROR(outputs.Stage(out_path, text));
//   PHOTOPOSE_RETURN_IF_ERROR(outputs.Commit());
//
// - AddOutput refuses, before any work, an output that is empty, a folder, in a folder that does
//   not exist, the same file as an input or as another output (compared after symlinks, and by
//   inode). Messages use the labels: "--out=marks.csv is the input --marks=marks.csv; ...".
// - A target that is a regular file or does not exist is staged as a temporary file beside the
//   file it names after symlinks, ".<name>.photopose-<pid>-XXXXXX", flushed to disk. Commit renames
//   every temporary over its target, so a symlink keeps pointing to the file it names, which is
//   replaced; a replaced file keeps its permissions, a new one gets rw-rw-rw- less the umask.
// - A target that exists and is not a regular file (a device such as /dev/null or /dev/full, a
//   FIFO, a terminal) is written in place at Commit, never replaced; /dev/stdout, /dev/stderr and
//   /dev/fd/N are written through the process's own descriptor, at its current offset. A FIFO
//   that nobody reads is an error, not a hang.
// - Nothing is renamed before every output is staged and every in-place output written; a
//   failure, or destruction without Commit, removes every temporary.
// - Temporaries left beside a target by a run that was killed (the pattern above with the pid of
//   a process that no longer exists) are removed when the target is added.

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.h"

namespace photopose {

// The text of one output as it is formatted: collected whole, or, for an output OutputFiles
// stages in pieces, written to its temporary file a piece at a time, so that a file of hundreds
// of MB is never held whole.
//
//   TextPieces* out;  // from OutputFiles::StageInPieces, or a TextPieces of one's own
//   for (...) {
//     out->text() += ...;
//     PHOTOPOSE_RETURN_IF_ERROR(out->Piece());
//   }
class TextPieces {
 public:
  // Collects the text whole (text() holds it all at the end).
  TextPieces() = default;
  TextPieces(const TextPieces&) = delete;
  TextPieces& operator=(const TextPieces&) = delete;

  // The text not yet written.
  std::string& text() { return text_; }
  // Writing a file: writes text() and empties it when it holds kPieceBytes or more. Collecting:
  // nothing.
  Status Piece() { return text_.size() >= kPieceBytes ? Flush() : Status::Ok(); }
  // Writing a file: writes text() and empties it. Collecting: nothing.
  Status Flush();
  // Appends `contents` after text() (writing a file: writes both at once).
  Status Write(std::string_view contents);
  // Whether the text goes to a file (then text() never holds much more than kPieceBytes).
  bool writes_file() const { return fd_ >= 0; }
  // Room for the text: `whole_bytes` (the whole file's estimate) when collecting; writing a file,
  // a piece and the record that may pass it.
  void Reserve(size_t whole_bytes) {
    text_.reserve(writes_file() ? kPieceBytes + (kPieceBytes >> 2) : whole_bytes);
  }

  static constexpr size_t kPieceBytes = size_t{4} << 20;  // bytes

 private:
  friend class OutputFiles;
  Status WriteToFile(std::string_view bytes) const;  // all of `bytes`, or the error naming name_
  int fd_ = -1;       // the temporary file written, or -1
  std::string name_;  // the output, in messages
  std::string text_;
};

class OutputFiles {
 public:
  OutputFiles() = default;
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;
  ~OutputFiles();

  // An input of the run. `label` names it in messages ("--marks"; empty: the path alone). Empty
  // paths are ignored; "-" (standard input) may be given once, a second one is an error.
  Status AddInput(const std::string& label, const std::string& path);
  // Declares an output and checks it (see above). Outputs must be added before they are staged.
  Status AddOutput(const std::string& label, const std::string& path);

  // Stages the complete contents of the output added as `path`.
  Status Stage(const std::string& path, std::string_view contents);
  // Stages the output added as `path` from format(out): what it appends to out->text() is
  // written to the temporary file at each out->Piece() that finds a piece full, and at the end
  // (in place and descriptor outputs are collected whole, as Stage's).
  Status StageInPieces(const std::string& path,
                       const std::function<Status(TextPieces* out)>& format);
  // Stages the output added as `path` by calling write(temporary_path), for writers that take a
  // path; messages that name the temporary file are rewritten to name `path`.
  Status StageWith(const std::string& path,
                   const std::function<Status(const std::string& temporary_path)>& write);

  // Writes the in-place outputs, then renames every temporary over its target. Every added
  // output must have been staged.
  Status Commit();
  // Removes every temporary; nothing is written. Also done by the destructor before Commit.
  void Abort();

 private:
  enum class Kind {
    kReplace,     // a regular file or a new one: temporary file + rename
    kInPlace,     // an existing node that is not a regular file: opened and written
    kDescriptor,  // /dev/stdout, /dev/stderr, /dev/fd/N: written to descriptor N
  };
  struct Output {
    std::string label;
    std::string path;  // as given
    Kind kind = Kind::kReplace;
    std::string target;     // kReplace: the file to replace, after symlinks; kInPlace: the node
    int descriptor = -1;    // kDescriptor
    std::string temporary;  // kReplace, once staged
    std::string contents;   // kInPlace, kDescriptor, once staged
    bool staged = false;
  };
  struct Input {
    std::string label;
    std::string path;
  };

  Output* Find(const std::string& path);  // the first output added as `path` not yet staged
  Status StageFailed(Status status);      // Abort(), then `status`

  std::vector<Input> inputs_;
  std::string standard_input_label_;  // the input read from "-", if any
  std::vector<Output> outputs_;
  bool committed_ = false;
};

// Writes one file as a transaction of one output (the rules above).
Status WriteFileAtomically(const std::string& path, const std::string& contents);

// One file of a folder written as a whole: its path inside the folder ("truth/frames.csv").
struct FolderFile {
  std::string relative_path;
  std::string contents;
};

// The pre-flight check of an output folder: `label` names it ("--out_dir"). Refuses a path that
// exists and is not a folder, the current folder or a folder that contains it, and a folder that
// holds entries WriteFolderAtomically cannot carry over (subfolders other than those of `files`,
// devices, FIFOs, sockets).
Status CheckOutputFolder(const std::string& label, const std::string& folder,
                         const std::vector<FolderFile>& files);

// Writes `files` into `folder` all or nothing, also against kill -9: the new folder is built
// beside the target (".<name>.photopose-<pid>-XXXXXX") with the new files and hard links to every
// other entry of the old folder, then swapped with it in one atomic step (renameat2
// RENAME_EXCHANGE) and the old one removed. A missing folder (and its missing parents) is
// created. Stale folders of killed runs are removed first.
Status WriteFolderAtomically(const std::string& label, const std::string& folder,
                             const std::vector<FolderFile>& files);

}  // namespace photopose
