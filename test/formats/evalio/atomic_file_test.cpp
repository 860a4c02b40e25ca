// Atomic output: complete file or nothing, temporary file removed on every
// path, errors name the path and the system error.
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/tum_stream.h"
#include "rvlio/outputs/output_stage.h"

namespace rvlio {
namespace {

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/rvlio_atomic_XXXXXX";
    dir_ = ::mkdtemp(tmpl);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string File(const std::string& name) const { return dir_ + "/" + name; }
  int EntryCount() const {
    int n = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir_)) (void)e, ++n;
    return n;
  }
  static std::string Read(const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  std::string dir_;
};

TEST_F(AtomicFileTest, WritesAndReplacesWholeFiles) {
  ASSERT_TRUE(WriteFileAtomically(File("out.txt"), "first\n").ok());
  EXPECT_EQ(Read(File("out.txt")), "first\n");
  ASSERT_TRUE(WriteFileAtomically(File("out.txt"), "second, longer content\n").ok());
  EXPECT_EQ(Read(File("out.txt")), "second, longer content\n");
  ASSERT_TRUE(WriteFileAtomically(File("empty.txt"), "").ok());
  EXPECT_EQ(Read(File("empty.txt")), "");
  EXPECT_EQ(EntryCount(), 2);
}

TEST_F(AtomicFileTest, FailureNamesThePathAndLeavesNothing) {
  const std::string path = File("no_such_dir/out.txt");
  Status s = WriteFileAtomically(path, "x");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("No such file or directory"), std::string::npos) << s.message();
  // Rename onto a directory fails after the temporary file was written.
  std::filesystem::create_directory(File("a_dir"));
  s = WriteFileAtomically(File("a_dir"), "x");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("a_dir"), std::string::npos) << s.message();
  EXPECT_EQ(EntryCount(), 1);  // only a_dir; no temporary file
}

TEST_F(AtomicFileTest, StreamingWriterCommitsLargeOutput) {
  AtomicFileWriter w;
  ASSERT_TRUE(w.Open(File("big.txt")).ok());
  std::string expected;
  const std::string chunk(1000, 'x');
  for (int i = 0; i < 3000; ++i) {  // 3 MB: several internal flushes
    const std::string line = std::to_string(i) + chunk + "\n";
    ASSERT_TRUE(w.Append(line).ok());
    expected += line;
  }
  EXPECT_FALSE(std::filesystem::exists(File("big.txt")));  // not visible before Commit
  ASSERT_TRUE(w.Commit().ok());
  EXPECT_EQ(Read(File("big.txt")), expected);
  EXPECT_EQ(EntryCount(), 1);
}

TEST_F(AtomicFileTest, UncommittedWriterDiscardsAndKeepsTheOldFile) {
  ASSERT_TRUE(WriteFileAtomically(File("keep.txt"), "old").ok());
  {
    AtomicFileWriter w;
    ASSERT_TRUE(w.Open(File("keep.txt")).ok());
    ASSERT_TRUE(w.Append(std::string(2 << 20, 'n')).ok());  // flushed to the temp file
    EXPECT_TRUE(std::filesystem::exists(w.temp_path()));
  }  // destroyed without Commit
  EXPECT_EQ(Read(File("keep.txt")), "old");
  EXPECT_EQ(EntryCount(), 1);
  // Moving a writer transfers the pending file.
  AtomicFileWriter a;
  ASSERT_TRUE(a.Open(File("moved.txt")).ok());
  ASSERT_TRUE(a.Append("moved").ok());
  AtomicFileWriter b = std::move(a);
  ASSERT_TRUE(b.Commit().ok());
  EXPECT_EQ(Read(File("moved.txt")), "moved");
  EXPECT_EQ(EntryCount(), 2);
}

// What an output path may be (docs/outputs.md): special files are refused
// and stay what they were; a link is followed and stays a link.
TEST_F(AtomicFileTest, FifoSocketAndFolderAreRefusedAndStayAsTheyWere) {
  namespace fs = std::filesystem;
  ASSERT_EQ(::mkfifo(File("fifo").c_str(), 0644), 0);
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(sock, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const std::string sock_path = File("sock");
  ASSERT_LT(sock_path.size(), sizeof(addr.sun_path));
  std::snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", sock_path.c_str());
  ASSERT_EQ(::bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  fs::create_directory(File("folder"));
  ASSERT_EQ(::symlink("fifo", File("to_fifo").c_str()), 0);
  const std::pair<const char*, const char*> cases[] = {{"fifo", "it is a FIFO (named pipe)"},
                                                       {"sock", "it is a socket"},
                                                       {"folder", "it is a folder"},
                                                       {"to_fifo", "it is a FIFO (named pipe)"}};
  for (const auto& [name, why] : cases) {
    const Status s = WriteFileAtomically(File(name), "data\n");
    ASSERT_FALSE(s.ok()) << name;
    EXPECT_EQ(s.code(), StatusCode::kInvalidInput) << name;
    EXPECT_EQ(s.message().rfind("cannot write '" + File(name) + "'", 0), 0u) << s.message();
    EXPECT_NE(s.message().find(why), std::string::npos) << s.message();
    TumStream stream;  // opening a FIFO for writing would block: refused first
    EXPECT_FALSE(stream.Open(File(name)).ok()) << name;
  }
  ::close(sock);
  EXPECT_TRUE(fs::is_fifo(File("fifo")));
  EXPECT_TRUE(fs::is_socket(File("sock")));
  EXPECT_TRUE(fs::is_directory(File("folder")));
  EXPECT_TRUE(fs::is_symlink(File("to_fifo")));
  EXPECT_EQ(EntryCount(), 4) << "no temporary file may stay";
}

TEST_F(AtomicFileTest, LinkIsFollowedToItsTargetAndStaysALink) {
  namespace fs = std::filesystem;
  fs::create_directory(File("real"));
  std::ofstream(File("real/target.txt")) << "old\n";
  ASSERT_EQ(::symlink("real/target.txt", File("link1").c_str()), 0);
  ASSERT_EQ(::symlink("link1", File("link2").c_str()), 0);  // a chain of links
  ASSERT_TRUE(WriteFileAtomically(File("link2"), "new\n").ok());
  EXPECT_TRUE(fs::is_symlink(File("link2")));
  EXPECT_TRUE(fs::is_symlink(File("link1")));
  EXPECT_EQ(Read(File("real/target.txt")), "new\n");
  // A dangling link: its target becomes a new file.
  ASSERT_EQ(::symlink("real/new.txt", File("dangling").c_str()), 0);
  ASSERT_TRUE(WriteFileAtomically(File("dangling"), "created\n").ok());
  EXPECT_TRUE(fs::is_symlink(File("dangling")));
  EXPECT_EQ(Read(File("real/new.txt")), "created\n");
  // A loop is refused.
  ASSERT_EQ(::symlink("loop_b", File("loop_a").c_str()), 0);
  ASSERT_EQ(::symlink("loop_a", File("loop_b").c_str()), 0);
  const Status loop = WriteFileAtomically(File("loop_a"), "x");
  EXPECT_EQ(loop.code(), StatusCode::kInvalidInput);
  EXPECT_NE(loop.message().find("too many levels of symbolic links"), std::string::npos)
      << loop.message();
  EXPECT_EQ(EntryCount(), 6);  // real, link1, link2, dangling, loop_a, loop_b
  EXPECT_EQ(std::distance(fs::directory_iterator(File("real")), fs::directory_iterator()), 2);
}

TEST_F(AtomicFileTest, StagedOutputsAreAllRefusedWhenOneNamesAFifo) {
  namespace fs = std::filesystem;
  std::ofstream(File("a.txt")) << "earlier\n";
  ASSERT_EQ(::mkfifo(File("b.txt").c_str(), 0644), 0);
  {
    OutputStage stage(dir_);
    ASSERT_TRUE(stage.Open().ok());
    ASSERT_TRUE(WriteFileAtomically(stage.Path("a.txt"), "new\n").ok());
    ASSERT_TRUE(WriteFileAtomically(stage.Path("b.txt"), "new\n").ok());
    const Status s = stage.Commit();
    EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
    EXPECT_NE(s.message().find("b.txt': it is a FIFO"), std::string::npos) << s.message();
  }
  EXPECT_EQ(Read(File("a.txt")), "earlier\n") << "all or none";
  EXPECT_TRUE(fs::is_fifo(File("b.txt")));
  EXPECT_EQ(EntryCount(), 2) << "the staging folder is removed";
}

// A command that fails removes the output folder it created (and the
// missing parents it created), not one that was there.
TEST_F(AtomicFileTest, OutputFolderRemovesWhatItCreatedWhenNothingWasWritten) {
  namespace fs = std::filesystem;
  {
    OutputFolder folder(File("new/nested/out"));
    ASSERT_TRUE(folder.Prepare().ok());
    EXPECT_TRUE(fs::is_directory(File("new/nested/out")));
  }
  EXPECT_FALSE(fs::exists(File("new"))) << "every folder it created is removed";
  fs::create_directory(File("existing"));
  {
    OutputFolder folder(File("existing/out"));
    ASSERT_TRUE(folder.Prepare().ok());
  }
  EXPECT_TRUE(fs::is_directory(File("existing")));
  EXPECT_FALSE(fs::exists(File("existing/out")));
  {
    OutputFolder folder(File("kept/out"));
    ASSERT_TRUE(folder.Prepare().ok());
    std::ofstream(File("kept/out/x")) << "x";
  }
  EXPECT_TRUE(fs::exists(File("kept/out/x"))) << "a folder holding anything stays";
  // An output folder that is a FIFO is refused, not replaced.
  ASSERT_EQ(::mkfifo(File("fifo_out").c_str(), 0644), 0);
  OutputFolder fifo(File("fifo_out"));
  const Status s = fifo.Prepare();
  EXPECT_EQ(s.message(), "output folder " + File("fifo_out") +
                             " is a FIFO (named pipe), not a folder");
  EXPECT_TRUE(fs::is_fifo(File("fifo_out")));
}

}  // namespace
}  // namespace rvlio
