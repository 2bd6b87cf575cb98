// luxeld's start-up checks on the files it trusts: the token file's mode and
// the data dir it creates (no server).
#include "service/daemon_config.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "service/data_dir_lock.h"

namespace luxel::service {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const char* name) {
  const fs::path d =
      fs::temp_directory_path() / (std::string(name) + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

unsigned mode_of(const fs::path& p) {
  struct stat st {};
  EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
  return st.st_mode & 07777;
}

// --host-memory-budget: bytes, -1 (half the machine's memory) unless given,
// 0 turns the check off, anything else is refused naming the flag.
TEST(DaemonConfig, HostMemoryBudgetIsBytes) {
  auto unset = parse_daemon_args({"--data-dir", "/tmp/x"});
  ASSERT_TRUE(unset) << unset.status().to_string();
  EXPECT_EQ(unset.value().host_memory_budget, -1);
  auto given = parse_daemon_args({"--data-dir", "/tmp/x", "--host-memory-budget", "2e9"});
  ASSERT_TRUE(given) << given.status().to_string();
  EXPECT_EQ(given.value().host_memory_budget, 2e9);
  // The byte sizes --import-memory-budget takes.
  auto sized = parse_daemon_args({"--data-dir", "/tmp/x", "--host-memory-budget", "8GiB"});
  ASSERT_TRUE(sized) << sized.status().to_string();
  EXPECT_EQ(sized.value().host_memory_budget, double(uint64_t{8} << 30));
  auto off = parse_daemon_args({"--data-dir", "/tmp/x", "--host-memory-budget", "0"});
  ASSERT_TRUE(off);
  EXPECT_EQ(off.value().host_memory_budget, 0);
  for (const char* bad : {"-1", "lots", ""}) {
    auto c = parse_daemon_args({"--data-dir", "/tmp/x", "--host-memory-budget", bad});
    ASSERT_FALSE(c) << bad;
    EXPECT_NE(c.status().message().find("--host-memory-budget"), std::string::npos)
        << c.status().message();
  }
}

TEST(DaemonConfig, TokenFileReadableByOthersIsRefused) {
  const fs::path dir = temp_dir("luxel-token-mode");
  const std::string token = (dir / "token").string();
  std::ofstream(token) << "s3cret\n";
  for (unsigned mode : {0644u, 0640u, 0604u}) {
    ASSERT_EQ(::chmod(token.c_str(), mode), 0);
    auto c = parse_daemon_args({"--data-dir", "/tmp/x", "--token-file", token});
    ASSERT_FALSE(c.is_ok()) << std::oct << mode;
    EXPECT_NE(c.status().message().find(token), std::string::npos) << c.status().message();
    EXPECT_NE(c.status().message().find(strprintf("mode %04o", mode)), std::string::npos)
        << c.status().message();
    EXPECT_NE(c.status().message().find("--allow-readable-token-file"), std::string::npos);

    auto allowed = parse_daemon_args(
        {"--data-dir", "/tmp/x", "--token-file", token, "--allow-readable-token-file"});
    ASSERT_TRUE(allowed.is_ok()) << allowed.status().to_string();
    EXPECT_EQ(allowed->token, "s3cret");
    ASSERT_EQ(allowed->warnings.size(), 1u);
    EXPECT_NE(allowed->warnings[0].find(token), std::string::npos) << allowed->warnings[0];
  }
  for (unsigned mode : {0600u, 0400u}) {
    ASSERT_EQ(::chmod(token.c_str(), mode), 0);
    auto c = parse_daemon_args({"--data-dir", "/tmp/x", "--token-file", token});
    ASSERT_TRUE(c.is_ok()) << c.status().to_string();
    EXPECT_TRUE(c->warnings.empty());
  }
  fs::remove_all(dir);
}

TEST(DaemonConfig, DataDirIsCreatedPrivateWhateverTheUmask) {
  const fs::path parent = temp_dir("luxel-data-mode");
  const fs::path data = parent / "data";
  const mode_t old = ::umask(0);
  auto lock = DataDirLock::acquire(data.string());
  ::umask(old);
  ASSERT_TRUE(lock.is_ok()) << lock.status().to_string();
  EXPECT_EQ(mode_of(data), 0700u);
  EXPECT_EQ(mode_of(data / "luxeld.lock"), 0600u);
  fs::remove_all(parent);
}

TEST(DaemonConfig, ImportBudgetAndTimeout) {
  auto d = parse_daemon_args({"--data-dir", "/tmp/x"});
  ASSERT_TRUE(d.is_ok()) << d.status().to_string();
  // Default: 1/8 of the machine's (or the cgroup's) memory; 300 s.
  EXPECT_EQ(d->import_memory_budget, scene::default_import_memory_budget());
  EXPECT_GT(d->import_memory_budget, 0u);
  EXPECT_EQ(d->import_timeout_s, 300);
  for (const auto& [text, bytes] :
       {std::pair{"3GiB", uint64_t{3} << 30}, std::pair{"512MiB", uint64_t{512} << 20},
        std::pair{"1048576", uint64_t{1} << 20}, std::pair{"1.5GiB", uint64_t{3} << 29}}) {
    auto c = parse_daemon_args({"--data-dir", "/tmp/x", "--import-memory-budget", text});
    ASSERT_TRUE(c.is_ok()) << text << ": " << c.status().to_string();
    EXPECT_EQ(c->import_memory_budget, bytes) << text;
  }
  for (const char* bad : {"", "lots", "1.5", "1000", "-3GiB"}) {
    auto c = parse_daemon_args({"--data-dir", "/tmp/x", "--import-memory-budget", bad});
    ASSERT_FALSE(c.is_ok()) << bad;
    EXPECT_NE(c.status().message().find("--import-memory-budget"), std::string::npos)
        << c.status().message();
  }
  auto t = parse_daemon_args({"--data-dir", "/tmp/x", "--import-timeout", "2.5"});
  ASSERT_TRUE(t.is_ok()) << t.status().to_string();
  EXPECT_EQ(t->import_timeout_s, 2.5);
  for (const char* bad : {"0", "-1", "soon"}) {
    auto c = parse_daemon_args({"--data-dir", "/tmp/x", "--import-timeout", bad});
    ASSERT_FALSE(c.is_ok()) << bad;
    EXPECT_NE(c.status().message().find("--import-timeout"), std::string::npos);
  }
}

}  // namespace
}  // namespace luxel::service
