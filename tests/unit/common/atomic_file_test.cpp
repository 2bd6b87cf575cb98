// write_file_atomic: whole files or nothing, no temporaries left behind.
#include "common/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include "temp_dir.h"

namespace luxel {
namespace {

using output::testing::read_bytes;
using output::testing::TempDir;
using output::testing::write_bytes;

TEST(AtomicFile, WritesAndReplacesWithoutTemporaries) {
  TempDir dir("atomic");
  const std::string path = dir.file("data.bin");
  const std::string first = "first version";
  ASSERT_TRUE(write_file_atomic(path, first.data(), first.size()).is_ok());
  EXPECT_EQ(read_bytes(path), first);
  const std::string second(100000, 'x');
  ASSERT_TRUE(write_file_atomic(path, second.data(), second.size()).is_ok());
  EXPECT_EQ(read_bytes(path), second);
  EXPECT_TRUE(dir.temporaries().empty());
}

TEST(AtomicFile, EmptyFileIsAllowed) {
  TempDir dir("atomic-empty");
  ASSERT_TRUE(write_file_atomic(dir.file("empty"), nullptr, 0).is_ok());
  EXPECT_TRUE(std::filesystem::exists(dir.file("empty")));
  EXPECT_EQ(std::filesystem::file_size(dir.file("empty")), 0u);
}

TEST(AtomicFile, StaleTemporaryFromACrashIsReused) {
  TempDir dir("atomic-stale");
  const std::string path = dir.file("data.bin");
  write_bytes(atomic_temp_path(path), "torn garbage from a crashed writer, longer than the data");
  const std::string data = "good";
  ASSERT_TRUE(write_file_atomic(path, data.data(), data.size()).is_ok());
  EXPECT_EQ(read_bytes(path), data);
  EXPECT_TRUE(dir.temporaries().empty());
}

TEST(AtomicFile, MissingDirectoryIsInvalidArgumentNamingThePath) {
  TempDir dir("atomic-missing");
  const std::string path = dir.file("no/such/dir/data.bin");
  const std::string data = "x";
  const Status st = write_file_atomic(path, data.data(), data.size());
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << st.to_string();
  EXPECT_NE(st.message().find(path), std::string::npos) << st.message();
}

TEST(AtomicFile, DirectoryAsTargetFailsAndLeavesNoTemporary) {
  TempDir dir("atomic-dir");
  std::filesystem::create_directory(dir.file("sub"));
  const std::string data = "x";
  const Status st = write_file_atomic(dir.file("sub"), data.data(), data.size());
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << st.to_string();
  EXPECT_NE(st.message().find(dir.file("sub")), std::string::npos) << st.message();
  EXPECT_TRUE(std::filesystem::is_directory(dir.file("sub")));
  EXPECT_TRUE(dir.temporaries().empty());
}

// The streaming form: what `fill` writes (seeking back, as an EXR's
// offset table does) is the file; a failing `fill` leaves the old file and
// no temporary.
TEST(AtomicFile, StreamedBytesReplaceTheFileOrNothing) {
  TempDir dir("atomic-with");
  const std::string path = dir.file("data.bin");
  write_bytes(path, "old");
  ASSERT_TRUE(write_file_atomic_with(path, [](int fd, const std::string&) {
                if (::write(fd, "xxxx-body", 9) != 9 || ::lseek(fd, 0, SEEK_SET) != 0 ||
                    ::write(fd, "head", 4) != 4)
                  return internal_error("write failed");
                return Status::ok();
              }).is_ok());
  EXPECT_EQ(read_bytes(path), "head-body");
  const Status st = write_file_atomic_with(path, [](int fd, const std::string&) {
    (void)::write(fd, "partial", 7);
    return resource_exhausted("encoder gave up");
  });
  EXPECT_EQ(st.code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(read_bytes(path), "head-body");
  EXPECT_TRUE(dir.temporaries().empty());
}

TEST(AtomicFile, EmptyPathIsInvalid) {
  EXPECT_EQ(write_file_atomic("", "x", 1).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace luxel
