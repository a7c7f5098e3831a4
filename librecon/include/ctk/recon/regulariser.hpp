#pragma once
// The penalty 1/2 lambda ||G x||^2 of the least-squares problem: G = identity (Tikhonov) or the
// discrete gradient (forward differences along x, y, z, none across the volume's boundary), in
// voxel units so lambda does not depend on the voxel size.
#include <string>

#include "ctk/core/volume.hpp"

namespace ctk {

enum class Regulariser { identity, gradient };
const char* to_string(Regulariser r);
/// "identity" or "gradient"; std::invalid_argument naming the others.
Regulariser regulariser_from_string(const std::string& name);

/// 1/2 ||G x||^2
double regulariser_value(Regulariser r, const Volume& x);
/// out += lambda G'G x
void add_regulariser_normal(Regulariser r, double lambda, const Volume& x, Volume& out);

}  // namespace ctk
