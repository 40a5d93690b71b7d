// The input log (core/file_read.h) and commitFile (core/temp_file.h): while the log is on, an atomic write never
// replaces a file this process read or was told is an input -- the same file, a hard link, a symbolic link to it,
// or the link it was read through -- and the input's bytes stay as they were. Files this process wrote are not
// inputs when read back. Off, nothing is recorded or refused.
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "temp_dir_test.h"
#include "visbuf/core/file_read.h"
#include "visbuf/core/temp_file.h"

namespace visbuf {
namespace {

namespace fs = std::filesystem;

class InputLogTest : public test::TempDirTest {
 protected:
  void SetUp() override {
    test::TempDirTest::SetUp();
    enableInputLog();
  }
  void TearDown() override {
    disableInputLog();  // the rest of this test program reads and writes without it
    test::TempDirTest::TearDown();
  }
  std::string file(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  static std::string contents(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  // A finished temporary file, committed onto `target`.
  Status commit(const std::string& target, const std::string& text) {
    const std::string tmp = file("tmp.part", text);
    return commitFile(tmp, target);
  }
};

TEST_F(InputLogTest, AReadFileIsNeverReplaced) {
  const std::string input = file("scene.bin", "input bytes");
  ASSERT_TRUE(readRegularFile(input));
  Status s = commit(input, "output");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(s.error().message.find("scene.bin: is an input of this command (read as '" + input + "'); refused"),
            std::string::npos)
      << s.error().message;
  EXPECT_EQ(contents(input), "input bytes");
  EXPECT_FALSE(fs::exists(dir_ / "tmp.part")) << "the temporary file is removed";
}

TEST_F(InputLogTest, HardLinksAndSymlinksOfAnInputAreRefused) {
  const std::string input = file("image.png", "pixels");
  ASSERT_TRUE(readRegularFile(input));
  const std::string hard = (dir_ / "hard.png").string(), soft = (dir_ / "soft.png").string();
  fs::create_hard_link(input, hard);
  fs::create_symlink(input, soft);
  EXPECT_FALSE(commit(hard, "x"));
  EXPECT_FALSE(commit(soft, "x"));
  EXPECT_EQ(contents(input), "pixels");
  EXPECT_TRUE(fs::is_symlink(soft));
  // A file of its own is fine.
  EXPECT_TRUE(commit((dir_ / "out.png").string(), "x"));
  EXPECT_EQ(contents((dir_ / "out.png").string()), "x");
}

TEST_F(InputLogTest, TheLinkAnInputWasReadThroughIsAnInput) {
  const std::string target = file("real.gltf", "{}");
  const std::string link = (dir_ / "link.gltf").string();
  fs::create_symlink(target, link);
  ASSERT_TRUE(readRegularFile(link));
  EXPECT_FALSE(commit(link, "pack"));
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(contents(target), "{}");
}

TEST_F(InputLogTest, NotedInputsAreRefusedUnreadWithTheirRole) {
  const std::string image = file("albedo.png", "never decoded");
  noteInputFile(image, "scene.gltf: image 0");
  Status s = commit(image, "json");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("(scene.gltf: image 0)"), std::string::npos) << s.error().message;
  ASSERT_TRUE(findInputFile(image));
  EXPECT_EQ(findInputFile(image)->role, "scene.gltf: image 0");
  EXPECT_FALSE(findInputFile((dir_ / "missing").string()));
}

TEST_F(InputLogTest, OwnOutputsReadBackAreNotInputs) {
  const std::string out = (dir_ / "bench.vbp").string();
  ASSERT_TRUE(commit(out, "first"));
  ASSERT_TRUE(readRegularFile(out));
  EXPECT_TRUE(commit(out, "second")) << "a file this process wrote, read back, may be written again";
  EXPECT_EQ(contents(out), "second");
}

TEST(InputLogOff, NothingIsRecordedOrRefused) {
  ASSERT_FALSE(inputLogEnabled());
  const fs::path dir = fs::temp_directory_path() / ("visbuf_input_log_off_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "a.bin").string(), tmp = (dir / "a.tmp").string();
  std::ofstream(path) << "a";
  ASSERT_TRUE(readRegularFile(path));
  std::ofstream(tmp) << "b";
  EXPECT_TRUE(commitFile(tmp, path));
  EXPECT_FALSE(findInputFile(path));
  EXPECT_TRUE(inputFiles().empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace visbuf
