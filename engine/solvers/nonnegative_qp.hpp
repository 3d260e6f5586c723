#pragma once

#include <Eigen/Dense>

#include "solvers/solver_status.hpp"

namespace deli {

// min 1/2 x'Qx + c'x subject to x >= 0, for symmetric positive semidefinite Q, by the
// Lawson-Hanson active-set method in QP form: finite termination, exact complementarity
// at the solution (x_i > 0 => (Qx + c)_i = 0 to rounding), and least-norm sub-solves so a
// singular Q (dependent normals, as at a corner) is handled. `tolerance` bounds the
// negative gradient accepted as zero.
[[nodiscard]] SolverStatus solve_nonnegative_qp(const Eigen::MatrixXd& Q, const Eigen::VectorXd& c,
                                                Eigen::VectorXd& x, double tolerance,
                                                int max_iterations = 0);

}  // namespace deli
