// Output files written whole or not at all. A reader (or a second run) never sees half a file:
// everything is written to a temporary file in the same directory and renamed into place, which
// POSIX makes atomic. A failed write (full disk, no permission) is an OutputError naming the file
// and the system's reason, never a silent success.
//
// What the path already is decides how (never is anything renamed over what is not a regular file):
// - nothing, or a regular file: the temporary file is renamed onto it;
// - a symbolic link (or a chain of them): followed; the link stays and what it finally names is
//   written as above, or as below when that is not a regular file;
// - a FIFO or a character device (a pipe to another program, /dev/stdout, /dev/null, a terminal):
//   written through, in place, as the text comes (a stream has no "whole file" to replace); a FIFO
//   without a reader is refused at once rather than waited for;
// - a directory, a block device or a socket: refused with an OutputError naming the path and what
//   it is (a CSV over a disk or a socket is never what was meant).
#pragma once

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace catenary_sim {

class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes `content` to `path` atomically (temporary file, flush, fsync, rename). Throws OutputError.
void write_file_atomically(const std::string& path, const std::string& content);

// Checks at start-up that `path` can be written later: the directory exists and accepts a new file
// (created and removed again), and `path` itself is not a directory (nor a block device or socket;
// a FIFO or character device must be writable, opened only when written). Throws OutputError naming the
// path and the reason. Leaves nothing behind.
void check_writable(const std::string& path);

// Where output for `path` goes: the path with its symbolic links followed (dangling: the file the
// link names, to be created) and whether it is written through as a stream (FIFO, character
// device) rather than renamed into place. Throws OutputError for a directory, a block device, a
// socket, or a link loop.
struct OutputTarget {
  std::string path;
  bool stream = false;
};
OutputTarget output_target(const std::string& path);

// Creates `dir` and its parents (mkdir -p); returns the directories it created, outermost first
// (none when `dir` was there). Throws OutputError.
std::vector<std::string> make_directories(const std::string& dir);

// A file being written: text goes to DIR/.NAME.tmp.XXXXXX; commit() flushes, fsyncs and renames it
// to `path` (to what a link at `path` names). Destroyed without commit() (an error, an exception) it
// removes the temporary file. A stream target (output_target()) is written directly instead.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);  // throws OutputError
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  std::FILE* file() {
    synced_ = false;
    return file_;
  }
  void write(const std::string& text);  // throws OutputError on a failed write
  // Hands what is written to the kernel and starts its writing to the disk without waiting, so
  // that flush() later waits for less; throws OutputError.
  void start_writeback();
  void flush();                         // writes everything to the disk; throws OutputError
  void commit();                        // flush() (unless done since the last write) and rename into place; throws OutputError
  const std::string& path() const { return path_; }

 private:
  std::string path_, tmp_, target_;
  std::FILE* file_ = nullptr;
  bool stream_ = false, synced_ = false;
};

// An exclusive advisory lock (flock) on DIR/.catenary_sim.lock, held while the object lives, so two
// runs never write into one output directory at once. Throws OutputError if another process holds
// it. The lock file stays (empty); the lock itself dies with the process.
class DirectoryLock {
 public:
  explicit DirectoryLock(const std::string& dir);
  ~DirectoryLock();
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;
  // A run that writes nothing after all (it diverged) takes back the lock file it made (one that
  // was there stays); the lock is held until the object goes.
  void remove_if_made();

 private:
  int fd_ = -1;
  bool made_ = false;
  std::string path_;
};

// Removes the directories make_directories created (`made`, outermost first), innermost first,
// each only if empty: a run that wrote nothing leaves no directory behind.
void remove_made_directories(const std::vector<std::string>& made);

}  // namespace catenary_sim
