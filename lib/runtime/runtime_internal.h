// Internal to lib/runtime: checks the per-vertex and per-texel loaders share.
#pragma once

#include "bundle.h"

#include <cstddef>
#include <string>
#include <vector>

namespace prt {

// The SH order L of a transfer layer of shape [rows, L*L, 3] (params.order, when set, must agree).
// Throws prt::Error(source, place, ...) naming the shape otherwise.
int transferLayerOrder(const Layer& layer, const std::string& source, const std::string& place);

// Throws prt::Error(source, "PLACE, ROW i", ...) for the first non-finite value; rows of rowValues floats.
void checkFiniteRows(const std::vector<float>& data, size_t rowValues, const std::string& source,
                     const std::string& place, const char* row);

} // namespace prt
