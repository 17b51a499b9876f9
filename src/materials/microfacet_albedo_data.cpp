// The checked-in albedo tables; regenerate with
//   kozu precompute microfacet-albedo -o src/materials/microfacet_albedo_data.inc
#include "materials/microfacet_albedo.h"

namespace kozu::albedo {

extern const float kConductorE[2][kRoughNodes][kMuNodes];
extern const float kDielectricE[2][kEtaNodes][kRoughNodes][kMuNodes];
extern const float kDielectricER[2][kEtaNodes][kRoughNodes][kMuNodes];

#include "materials/microfacet_albedo_data.inc"

}  // namespace kozu::albedo
