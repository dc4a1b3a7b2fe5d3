// file_root (the guard of the server's file services): relative paths resolve under the root;
// `..`, absolute paths elsewhere, symlinks leading out and dangling symlinks are refused with
// the reason; the default follows $ROS_HOME / $HOME.
#include "../../src/ros/server/file_root.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "fragg_map/errors.h"

namespace {

namespace fs = std::filesystem;
using fragg::ros::defaultFileRoot;
using fragg::ros::prepareFileRoot;
using fragg::ros::resolveUnderRoot;

class FileRootTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::path(FRAGG_TEST_TMP) / "file_root_test";
    fs::remove_all(base_);
    fs::create_directories(base_ / "outside");
    root_ = prepareFileRoot((base_ / "maps").string());  // created here
  }
  void TearDown() override { fs::remove_all(base_); }

  // The message of the refusal of `requested` ("" when it was not refused).
  std::string refusal(const std::string& requested) const {
    try {
      resolveUnderRoot(root_, requested);
    } catch (const fragg::InvalidArgument& e) {
      return e.what();
    }
    return "";
  }

  fs::path base_;
  std::string root_;
};

TEST_F(FileRootTest, PrepareCreatesTheFolderAndGivesItsRealPath) {
  EXPECT_TRUE(fs::is_directory(root_));
  EXPECT_EQ(fs::path(root_), fs::canonical(base_ / "maps"));
  // A root reached through a symlink becomes the link's target.
  fs::create_directory_symlink(base_ / "maps", base_ / "link_to_maps");
  EXPECT_EQ(prepareFileRoot((base_ / "link_to_maps").string()), root_);
  // A file where the folder should be.
  std::ofstream(base_ / "a_file") << "x";
  EXPECT_THROW(prepareFileRoot((base_ / "a_file").string()), fragg::IoError);
  EXPECT_THROW(prepareFileRoot(""), fragg::IoError);
}

TEST_F(FileRootTest, RelativePathsResolveUnderTheRoot) {
  EXPECT_EQ(resolveUnderRoot(root_, "map.fgm"), (fs::path(root_) / "map.fgm").string());
  EXPECT_EQ(resolveUnderRoot(root_, "robots/a/map.bt"),
            (fs::path(root_) / "robots/a/map.bt").string());
  EXPECT_EQ(resolveUnderRoot(root_, "./x/../map.fgm"), (fs::path(root_) / "map.fgm").string());
}

TEST_F(FileRootTest, AbsolutePathsInsideTheRootAreAccepted) {
  const std::string inside = (fs::path(root_) / "sub" / "m.fgm").string();
  EXPECT_EQ(resolveUnderRoot(root_, inside), inside);
}

TEST_F(FileRootTest, DotDotOutOfTheRootIsRefused) {
  for (const std::string bad :
       {"../outside/map.fgm", "../../etc/passwd", "a/../../map.fgm", ".."}) {
    const std::string why = refusal(bad);
    EXPECT_NE(why.find("'..' leads to"), std::string::npos) << bad << ": " << why;
    EXPECT_NE(why.find(root_), std::string::npos) << why;  // names the root
  }
  // A sibling folder whose name starts with the root's name is outside too.
  fs::create_directories(base_ / "maps2");
  EXPECT_NE(refusal((base_ / "maps2" / "m.fgm").string()).find("absolute path outside"),
            std::string::npos);
}

TEST_F(FileRootTest, AbsolutePathsOutsideAreRefused) {
  EXPECT_NE(refusal("/etc/passwd").find("absolute path outside"), std::string::npos);
  EXPECT_NE(refusal("/tmp/map.fgm").find("absolute path outside"), std::string::npos);
  EXPECT_NE(refusal((base_ / "outside" / "m.fgm").string()).find("absolute path outside"),
            std::string::npos);
}

TEST_F(FileRootTest, SymlinksLeadingOutAreRefused) {
  fs::create_directory_symlink(base_ / "outside", fs::path(root_) / "escape_dir");
  std::ofstream(base_ / "outside" / "secret.fgm") << "x";
  fs::create_symlink(base_ / "outside" / "secret.fgm", fs::path(root_) / "escape.fgm");
  EXPECT_NE(refusal("escape_dir/map.fgm").find("symbolic link leads to"), std::string::npos);
  EXPECT_NE(refusal("escape.fgm").find("symbolic link leads to"), std::string::npos);
  // A symlink that stays inside is fine (resolved to its target).
  fs::create_directories(fs::path(root_) / "real");
  fs::create_directory_symlink(fs::path(root_) / "real", fs::path(root_) / "alias");
  EXPECT_EQ(resolveUnderRoot(root_, "alias/m.fgm"), (fs::path(root_) / "real" / "m.fgm").string());
}

TEST_F(FileRootTest, DanglingSymlinksAreRefused) {
  fs::create_symlink(base_ / "outside" / "not_yet.fgm", fs::path(root_) / "later.fgm");
  EXPECT_NE(refusal("later.fgm").find("symbolic link to nothing"), std::string::npos);
  fs::create_directory_symlink(base_ / "no_such_dir", fs::path(root_) / "gone");
  EXPECT_NE(refusal("gone/m.fgm").find("symbolic link to nothing"), std::string::npos);
}

TEST_F(FileRootTest, EmptyPathAndTheRootItselfAreRefused) {
  EXPECT_EQ(refusal(""), "empty path");
  EXPECT_NE(refusal(".").find("names the folder itself"), std::string::npos);
  EXPECT_NE(refusal(root_).find("names the folder itself"), std::string::npos);
  EXPECT_NE(refusal("sub/..").find("names the folder itself"), std::string::npos);
}

TEST(FileRootDefault, FollowsRosHomeThenHome) {
  const char* old_ros_home = getenv("ROS_HOME");
  const char* old_home = getenv("HOME");
  const std::string saved_ros_home = old_ros_home ? old_ros_home : "";
  const std::string saved_home = old_home ? old_home : "";
  setenv("ROS_HOME", "/data/ros", 1);
  EXPECT_EQ(defaultFileRoot(), "/data/ros/fragg_map");
  unsetenv("ROS_HOME");
  setenv("HOME", "/home/robot", 1);
  EXPECT_EQ(defaultFileRoot(), "/home/robot/.ros/fragg_map");
  if (old_ros_home) setenv("ROS_HOME", saved_ros_home.c_str(), 1);
  if (old_home)
    setenv("HOME", saved_home.c_str(), 1);
  else
    unsetenv("HOME");
}

}  // namespace
