#pragma once
// How every combabc command writes files, under one rule: no command deletes, truncates or
// replaces a file or directory it did not create, unless the user named that path with
// --overwrite, and then only that path (docs/history.md, "Output files").
//
// Single files (simulate's CSV) go through AtomicFile; directories of results (export, and the
// report, whose Python script draws into a private folder that WriteReport then publishes) through
// OutputDirectory, which records what combabc wrote in a manifest so that a later run replaces
// only those files.
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace combabc {

// What an output path names now. `--overwrite` replaces regular files only: a character device or
// a FIFO (/dev/null, /dev/stdout into a pipe) is written into, never replaced, as cp and tee do; a
// directory, a block device or a socket is refused (docs/history.md, "Output files"). A symlink
// counts as what it points to, except that a link to a regular file (or a dangling one) is itself
// the path that is replaced.
enum class OutputPathKind { kMissing, kRegularFile, kStream };
// Throws combabc::Error (kCantCreate, naming `path`) for what can never be an output file.
OutputPathKind ClassifyOutputPath(const std::string& path);

// A file written under a unique temporary name in its target's directory, then fsync'd and renamed
// onto the target. The temporary is created with O_CREAT | O_EXCL | O_NOFOLLOW, so nothing that
// already exists (a file, or a symlink planted at a guessable name) is ever opened or truncated;
// the rename replaces a path, never what a symlink there points to. A target that is a stream
// (OutputPathKind::kStream) is instead written into directly at Commit(), with or without
// `replace`: nothing is replaced there. Errors are combabc::Error (kCantCreate, kIo) naming the
// target.
class AtomicFile {
 public:
  // Creates the temporary. An existing `path` is replaced only when `replace`; without it, a file
  // already there is refused now (before any work) and again, atomically, at Commit().
  AtomicFile(std::string path, bool replace);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();  // removes the temporary unless committed

  std::ostream& out() { return buffer_; }
  const std::string& path() const { return path_; }
  const std::string& temporary_path() const { return temp_path_; }

  // Writes the text buffered so far into the temporary, so that another process can read it there
  // (or, for a file left empty, write it: the export's NetCDF script). Commit() adds what follows.
  void Flush();

  // Writes the buffered text, fsyncs it and renames it onto path(); a refusal (kCantCreate) leaves
  // what is at path() as it was.
  void Commit();

 private:
  std::string path_;
  std::string temp_path_;
  bool replace_;
  bool stream_ = false;  // the target is a character device or FIFO, written into at Commit()
  int fd_ = -1;
  int pending_ = -1;  // the temporary's slot for RemovePendingOutputs (-1: none)
  std::ostringstream buffer_;
};

// Removes now every temporary of a live AtomicFile, then every directory a live OutputDirectory
// created and has not committed (if empty): for a signal handler about to end the process, which
// runs no destructors (the CLI's, on Ctrl-C outside a wave), so that an interrupted export leaves
// nothing behind. Async-signal-safe: it only reads fixed slots and calls unlink and rmdir.
void RemovePendingOutputs() noexcept;

// `text` into `path` through an AtomicFile: an existing `path` is replaced only when `overwrite`.
void WriteFileAtomically(const std::string& path, std::string_view text, bool overwrite);

// A directory combabc writes its own set of files into (an export, a report). Files are staged as
// AtomicFiles and appear together at Commit(); a failure before that leaves the directory as it
// was (and removes it if this object created it). The directory's manifest (kManifest, one file
// name a line) lists the files combabc wrote there:
//  - missing: the directory is created (its parent must exist);
//  - with a manifest: Commit() replaces the files it lists, and removes those it lists that this
//    commit does not write again (a previous report's extra waves), nothing else;
//  - empty, without a manifest: used as if created;
//  - not empty, without a manifest: refused (kCantCreate) unless `overwrite`: then combabc's files
//    replace same-named files and nothing else is touched.
// A file of the same name as one being written that the manifest does not list is replaced only
// with `overwrite`. The directory itself is never removed unless this object created it.
class OutputDirectory {
 public:
  static constexpr const char* kManifest = ".combabc-manifest";
  // Every temporary combabc makes in an output directory (AtomicFile's) starts with this, then
  // the making process's id: ".combabc-tmp-<pid>-<random>-<name>". A directory holding nothing
  // else (left by a killed command) counts as empty, and opening one (or one with a manifest)
  // removes those of them whose process has ended.
  static constexpr const char* kTemporaryPrefix = ".combabc-tmp-";

  // What a refusal of a foreign directory suggests (the report of `run` has no --overwrite).
  static constexpr const char* kDefaultHint =
      "choose another directory, or use --overwrite to add combabc's files to it";

  OutputDirectory(std::string path, bool overwrite);
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;
  ~OutputDirectory();

  // The same checks as the constructor, changing nothing: lets a long job (a calibration run)
  // find out before it starts that its output directory would be refused at the end.
  static void Check(const std::string& path,
                    bool overwrite,
                    const std::string& hint = kDefaultHint);

  const std::string& path() const { return path_; }
  // A stream for file `name` (a plain file name), written at Commit().
  std::ostream& Add(const std::string& name);
  // The temporary that `name` (added before) is staged in, holding what was written to it so far:
  // a helper process reads a staged file there or writes an added, empty one (the NetCDF export).
  // It is renamed into place at Commit() with the others.
  std::string StagedPath(const std::string& name);
  // Whether `name` is staged (added and not discarded).
  bool Has(const std::string& name) const;
  // Unstages `name` (a file a helper process could not write); its temporary is removed.
  void Discard(const std::string& name);
  void Commit();

 private:
  std::string path_;
  bool overwrite_;
  bool created_ = false;
  bool committed_ = false;
  int pending_ = -1;  // a created directory's slot for RemovePendingOutputs (-1: none)
  std::set<std::string> previous_;  // the manifest's names when the directory was opened
  std::vector<std::pair<std::string, std::unique_ptr<AtomicFile>>> staged_;
};

}  // namespace combabc
