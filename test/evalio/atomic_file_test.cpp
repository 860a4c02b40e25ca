// Atomic output: complete file or nothing, temporary file removed on every
// path, errors name the path and the system error.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "rvlio/formats/atomic_file.h"

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

}  // namespace
}  // namespace rvlio
