// libFuzzer target: the .kvox voxel-grid reader (versions 1 and 2) and the MIP chain built from what it returns,
// in float and compact storage. Input loads or throws InputError.
#include "core/error.h"
#include "media/voxel_grid.h"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const kozu::VoxelGrid g =
        kozu::VoxelGrid::from_kvox_bytes("fuzz.kvox", std::string_view(reinterpret_cast<const char*>(data), size));
    kozu::build_mip_chain(g);
    kozu::VoxelGrid c = g;  // compact storage and its chain (a version 2 input already is compact)
    c.compact();
    kozu::build_mip_chain(c);
  } catch (const kozu::InputError&) {
  }
  return 0;
}
