#pragma once

#include <vector>

#include "constraints/constraint.hpp"

namespace deli {

// reflect() (generalized operator, E = H) for a cluster of one inequality row and no
// equality rows: an isolated pair of hard spheres, or one particle at a wall, the common
// collision of a hard-sphere fluid. Closed form: with normal velocity v_n = grad g . M^-1 p
// below -tolerance, the impulse lambda = -2 v_n / (grad g . M^-1 grad g) along grad g
// reverses v_n and keeps H; otherwise nothing changes. reflect() reaches the same impulse
// through its dense QP (equal up to rounding: the sums run in another order).
// `inverse_mass` is per particle (global numbering); p is updated in place. Returns the
// impulse along the row's gradient (0 when the row was not approaching), or a negative
// value when the row has no direction (coincident particles): the caller takes reflect().
// With `left_approaching` (where the row has a direction): whether the row still approaches
// after it, i.e. whether a second call would change p again.
double reflect_lone_row(const Constraint& row, const Vec3* x, const Box& box,
                        const std::vector<double>& mass, double tolerance, Vec3* p,
                        bool* left_approaching = nullptr);

}  // namespace deli
