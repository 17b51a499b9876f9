// The table that maps a shape's JSON "type" to its parser (core/registry.h): the geometry keys of sphere,
// quad, polygon and mesh (docs/scene-format.md). The keys every shape shares (material, emission, media) are
// the scene loader's; it reads them before calling parse_shape, which then reports any key no one read.
#pragma once

#include "core/registry.h"
#include "geometry/shape.h"

#include <string>

namespace kozu {

// The shape's geometry; a mesh file is read, transformed and checked by the returned job. *type receives the
// shape's type.
Deferred<Shape> parse_shape(const JsonObject& desc, std::string* type);

}  // namespace kozu
