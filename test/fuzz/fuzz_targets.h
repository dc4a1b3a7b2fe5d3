// Fuzz entry functions, one a file (fuzz_<name>.cpp): each reads the bytes as one input of a
// reader, the way the project's callers do, and catches the errors those callers catch
// (fragg::IoError, fragg::InvalidArgument). Any other exception escapes, and a crash is a crash:
// both are findings. The same functions run under libFuzzer (FRAGG_FUZZ=ON, fuzz_main.cpp) and
// over the committed corpora in the normal build (corpus_replay_test.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fragg::fuzz {

/// A .fgm map (every version the loader reads); the input is the file without its CRC-32 footer,
/// which the target appends so that the fuzzer reaches the fields behind the checksum.
int fgm(const uint8_t* data, size_t size);
/// A kept-scan record (byte 0: format version and mode) read from memory, or a spill file.
int scan(const uint8_t* data, size_t size);
int pcd(const uint8_t* data, size_t size);
int ply(const uint8_t* data, size_t size);
int xyz(const uint8_t* data, size_t size);
int kittiBin(const uint8_t* data, size_t size);
/// An OctoMap ScanGraph (.graph), through openDataset and every scan of it.
int scanGraph(const uint8_t* data, size_t size);
/// The pose files: TUM (dataset folders), `correct --poses`, KITTI poses, calib and times.
int poses(const uint8_t* data, size_t size);
/// `--waypoints` files of `fragg_map collide`.
int waypoints(const uint8_t* data, size_t size);
int obj(const uint8_t* data, size_t size);
/// Map::insert on the CPU backend (and, with kept scans, remove and correctPoses): the layout
/// is in fuzz_insert.cpp. A broken invariant aborts.
int insertScan(const uint8_t* data, size_t size);
#ifdef FRAGG_FUZZ_HAVE_ROS_MSGS
/// Serialised sensor_msgs/PointCloud2 bytes -> ros::serialization -> cloudFromMsg.
int cloudMsg(const uint8_t* data, size_t size);
#endif

using EntryFunction = int (*)(const uint8_t*, size_t);
struct Target {
  std::string name;  ///< corpus folder under test/fuzz/corpus/ and binary fragg_fuzz_<name>
  EntryFunction run;
};
/// Every target built in this configuration.
std::vector<Target> targets();

}  // namespace fragg::fuzz
