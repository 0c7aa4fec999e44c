// Output files onto targets that are not regular files (output_files.hpp): a FIFO is written
// through and stays a FIFO, a symbolic link stays a link and its target gets the text, a FIFO
// without a reader and a directory are refused at once, and a failed write leaves the target as it
// was. All in a temporary directory: no system file (/dev/null) is ever touched.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <thread>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "catenary_sim/core/output/output_files.hpp"

using namespace catenary_sim;

namespace {

struct TempDir {
  std::string path;
  TempDir() {
    char name[] = "/tmp/catenary_sim_targets_XXXXXX";
    path = ::mkdtemp(name);
  }
  ~TempDir() { std::system(("rm -rf '" + path + "'").c_str()); }
};

std::string read_all(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

mode_t lmode(const std::string& path) {
  struct stat st {};
  EXPECT_EQ(::lstat(path.c_str(), &st), 0) << path;
  return st.st_mode;
}

// The reader a FIFO needs, opened without blocking before the writer comes; what the writer left
// in the pipe (well below its 64 kB buffer) is read after it closed. No thread, so a FIFO
// replaced by a file is a failure, not a hang.
struct FifoReader {
  int fd = -1;
  explicit FifoReader(const std::string& path) : fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK)) {}
  ~FifoReader() {
    if (fd >= 0) ::close(fd);
  }
  std::string drain() {
    std::string out;
    char buf[4096];
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) out.append(buf, static_cast<std::size_t>(n));
    return out;
  }
};

}  // namespace

TEST(OutputTargets, FifoIsWrittenThroughAndStaysAFifo) {
  TempDir d;
  const std::string fifo = d.path + "/pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  FifoReader reader(fifo);
  ASSERT_GE(reader.fd, 0);
  write_file_atomically(fifo, "x_m,uplift_mm\n0,1\n");
  EXPECT_EQ(reader.drain(), "x_m,uplift_mm\n0,1\n");
  EXPECT_TRUE(S_ISFIFO(lmode(fifo))) << "the FIFO was replaced";
}

TEST(OutputTargets, FifoWithoutReaderIsRefusedAtOnce) {
  TempDir d;
  const std::string fifo = d.path + "/pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  check_writable(fifo);  // writable: the reader may come later
  const auto t0 = std::chrono::steady_clock::now();
  try {
    write_file_atomically(fifo, "text\n");
    FAIL() << "accepted a FIFO without a reader";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("no reader"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(fifo), std::string::npos) << e.what();
  }
  // A hang would be cut by the test's timeout; the refusal itself takes no waiting.
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  EXPECT_TRUE(S_ISFIFO(lmode(fifo)));
  // No temporary file left beside it.
  EXPECT_EQ(std::system(("test -z \"$(ls -A '" + d.path + "' | grep -v '^pipe$')\"").c_str()), 0);
}

TEST(OutputTargets, SymlinkIsKeptAndItsTargetWritten) {
  TempDir d;
  const std::string file = d.path + "/real.csv", link = d.path + "/link.csv";
  std::ofstream(file) << "old\n";
  ASSERT_EQ(::symlink("real.csv", link.c_str()), 0);  // relative, as ln -s makes them
  write_file_atomically(link, "new\n");
  EXPECT_TRUE(S_ISLNK(lmode(link))) << "the link was replaced by a file";
  EXPECT_TRUE(S_ISREG(lmode(file)));
  EXPECT_EQ(read_all(file), "new\n");
  // A chain of links, and a dangling one (its target is created).
  const std::string link2 = d.path + "/link2.csv", dangling = d.path + "/dangling.csv";
  ASSERT_EQ(::symlink(link.c_str(), link2.c_str()), 0);
  write_file_atomically(link2, "newer\n");
  EXPECT_TRUE(S_ISLNK(lmode(link2)));
  EXPECT_TRUE(S_ISLNK(lmode(link)));
  EXPECT_EQ(read_all(file), "newer\n");
  ASSERT_EQ(::symlink("made.csv", dangling.c_str()), 0);
  write_file_atomically(dangling, "made\n");
  EXPECT_TRUE(S_ISLNK(lmode(dangling)));
  EXPECT_EQ(read_all(d.path + "/made.csv"), "made\n");
}

TEST(OutputTargets, SymlinkToFifoWritesThroughTheFifo) {
  TempDir d;
  const std::string fifo = d.path + "/pipe", link = d.path + "/link";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  ASSERT_EQ(::symlink(fifo.c_str(), link.c_str()), 0);
  EXPECT_TRUE(output_target(link).stream);
  FifoReader reader(fifo);
  ASSERT_GE(reader.fd, 0);
  write_file_atomically(link, "through\n");
  EXPECT_EQ(reader.drain(), "through\n");
  EXPECT_TRUE(S_ISLNK(lmode(link)));
  EXPECT_TRUE(S_ISFIFO(lmode(fifo)));
}

TEST(OutputTargets, DirectoryAndLinkLoopAreRefused) {
  TempDir d;
  const std::string sub = d.path + "/sub", link = d.path + "/to_sub", loop = d.path + "/loop";
  ASSERT_EQ(::mkdir(sub.c_str(), 0700), 0);
  ASSERT_EQ(::symlink(sub.c_str(), link.c_str()), 0);
  ASSERT_EQ(::symlink(loop.c_str(), loop.c_str()), 0);
  for (const std::string& p : {sub, link, loop}) {
    EXPECT_THROW(check_writable(p), OutputError) << p;
    EXPECT_THROW(write_file_atomically(p, "x\n"), OutputError) << p;
  }
  EXPECT_TRUE(S_ISDIR(lmode(sub)));
  EXPECT_TRUE(S_ISLNK(lmode(link)));
  try {
    write_file_atomically(link, "x\n");
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("a directory"), std::string::npos) << e.what();
  }
}

TEST(OutputTargets, ReaderGoneIsAnErrorNotADeath) {
  // A reader that closes the pipe at once: the write fails with EPIPE as an OutputError (SIGPIPE
  // would end the test program).
  TempDir d;
  const std::string fifo = d.path + "/pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int rd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(rd, 0);
  AtomicFile f(fifo);
  ::close(rd);
  EXPECT_THROW(
      {
        f.write(std::string(1 << 20, 'x'));
        f.commit();
      },
      OutputError);
}
