// Fuzz entry functions, one a file (fuzz_<name>.cpp): each reads the bytes as one input of a
// reader, the way the project's callers do, and catches the errors those callers catch
// (fragg::IoError, fragg::InvalidArgument). Any other exception escapes, and a crash is a crash:
// both are findings. The same functions run under libFuzzer (FRAGG_FUZZ=ON, fuzz_main.cpp) and
// over the committed corpora in the normal build (corpus_replay_test.cpp).
//
// The convention every entry follows (a new target too): `bool name(const uint8_t* data,
// size_t size)` returns true when the input parsed (the reader returned; for a target that
// tries several readers, at least one did) and false when it was refused (a project error
// caught, or bytes the target cannot hand to the reader at all). libFuzzer's
// LLVMFuzzerTestOneInput ignores the result and returns 0; the corpus replay asserts that every
// committed seed_* input parses, so a reader that refuses valid files fails it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fragg::fuzz {

/// A .fgm map (every version the loader reads); the input is the file without its CRC-32 footer,
/// which the target appends so that the fuzzer reaches the fields behind the checksum.
bool fgm(const uint8_t* data, size_t size);
/// A kept-scan record (byte 0: format version and mode) read from memory, or a spill file.
bool scan(const uint8_t* data, size_t size);
bool pcd(const uint8_t* data, size_t size);
bool ply(const uint8_t* data, size_t size);
bool xyz(const uint8_t* data, size_t size);
bool kittiBin(const uint8_t* data, size_t size);
/// An OctoMap ScanGraph (.graph), through openDataset and every scan of it.
bool scanGraph(const uint8_t* data, size_t size);
/// The pose files: TUM (dataset folders), `correct --poses`, KITTI poses, calib and times.
bool poses(const uint8_t* data, size_t size);
/// `--waypoints` files of `fragg_map collide`.
bool waypoints(const uint8_t* data, size_t size);
bool obj(const uint8_t* data, size_t size);
/// Map::insert on the CPU backend (and, with kept scans, remove and correctPoses): the layout
/// is in insert_input.h. "Parsed": the map took the input's parameters (no InvalidArgument). A
/// broken invariant aborts.
bool insertScan(const uint8_t* data, size_t size);
#ifdef FRAGG_FUZZ_HAVE_ROS_MSGS
/// Serialised sensor_msgs/PointCloud2 bytes -> ros::serialization -> cloudFromMsg.
bool cloudMsg(const uint8_t* data, size_t size);
#endif

using EntryFunction = bool (*)(const uint8_t*, size_t);  ///< true: parsed, false: refused
struct Target {
  std::string name;  ///< corpus folder under test/fuzz/corpus/ and binary fragg_fuzz_<name>
  EntryFunction run;
};
/// Every target built in this configuration.
std::vector<Target> targets();

}  // namespace fragg::fuzz
