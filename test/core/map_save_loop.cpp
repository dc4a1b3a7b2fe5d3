// Helper of the autosave kill test (map_image_test.cpp): inserts scan after scan of
// save_loop_scene.h and after each one saves the map as the server's autosave does
// (Map::image, then writeMapImage: temporary file, fsync, rename), forever, until killed.
// Usage: fragg_map_save_loop PATH
#include <cstdio>
#include <exception>

#include "fragg_map/map_image.h"
#include "save_loop_scene.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s PATH\n", argv[0]);
    return 2;
  }
  try {
    fragg::Map map(fragg::test::saveLoopParams());
    for (int k = 0;; ++k) {
      fragg::test::insertSaveLoopScan(map, k);
      fragg::writeMapImage(map.image(), argv[1]);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_save_loop: %s\n", e.what());
    return 1;
  }
}
