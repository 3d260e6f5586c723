#include "solvers/position_problem.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/error.hpp"

namespace deli {

namespace {

// One word per kind (kind_name has spaces, which a word-by-word reader cannot take).
constexpr std::pair<ConstraintKind, const char*> kKindWords[] = {
    {ConstraintKind::rod, "rod"},
    {ConstraintKind::anchor, "anchor"},
    {ConstraintKind::sphere_pair, "sphere_pair"},
    {ConstraintKind::plane, "plane"},
    {ConstraintKind::inside_sphere, "inside_sphere"},
    {ConstraintKind::outside_sphere, "outside_sphere"},
    {ConstraintKind::linear_pair, "linear_pair"}};

const char* kind_word(ConstraintKind kind) {
  for (const auto& [k, word] : kKindWords) {
    if (k == kind) return word;
  }
  return "?";
}

void write_vec(std::ostream& out, const Vec3& v) {
  out << ' ' << v.x << ' ' << v.y << ' ' << v.z;
}

// The file read line by line, each line as words; comments (#) and blank lines skipped.
class ProblemReader {
 public:
  explicit ProblemReader(const std::string& path) : path_(path), in_(path) {
    if (!in_) {
      throw InputError(path + ": cannot read the solver problem (" + std::strerror(errno) + ")");
    }
  }

  // The next line's words; its first must be `keyword` (when not empty) and it must have
  // `count` words after it.
  std::vector<std::string> line(const std::string& keyword, std::size_t count,
                                const std::string& expected) {
    std::string text;
    while (std::getline(in_, text)) {
      ++line_;
      std::istringstream words(text);
      std::vector<std::string> out;
      for (std::string w; words >> w;) out.push_back(w);
      if (out.empty() || out.front().front() == '#') continue;
      if (!keyword.empty()) {
        if (out.front() != keyword) fail("expected '" + keyword + "' (" + expected + ")");
        out.erase(out.begin());
      }
      if (out.size() != count) {
        fail("expected " + std::to_string(count) + " values (" + expected + "), found " +
             std::to_string(out.size()));
      }
      return out;
    }
    ++line_;
    fail("the file ends where " + (keyword.empty() ? expected : "'" + keyword + "'") +
         " was expected");
  }

  double number(const std::string& word) {
    char* end = nullptr;
    const double value = std::strtod(word.c_str(), &end);
    if (word.empty() || *end != '\0') fail("'" + word + "' is not a number");
    return value;
  }
  long long integer(const std::string& word, long long lowest, long long highest) {
    char* end = nullptr;
    const long long value = std::strtoll(word.c_str(), &end, 10);
    if (word.empty() || *end != '\0' || value < lowest || value > highest) {
      fail("'" + word + "' is not an integer in [" + std::to_string(lowest) + ", " +
           std::to_string(highest) + "]");
    }
    return value;
  }
  Vec3 vec(const std::vector<std::string>& words, std::size_t first) {
    return {number(words[first]), number(words[first + 1]), number(words[first + 2])};
  }
  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(located(path_, line_,
                             message + "; the file is a solver problem as "
                                       "deli writes it (deli-failed-solve-stepN.txt)"));
  }

 private:
  std::string path_;
  std::ifstream in_;
  long line_ = 0;
};

}  // namespace

void write_position_problem(std::ostream& out, const PositionProblem& problem) {
  out.precision(17);
  out << "# deli failed position update: step " << problem.step << ", h " << problem.h << "\n"
      << "# one cluster's problem (engine/solvers/position_problem.hpp); solve it again with "
         "`deli solve-problem FILE`\n";
  out << "step " << problem.step << "\n";
  out << "h " << problem.h << "\n";
  out << "tolerance " << problem.tolerance << "\n";
  out << "newton_limit " << problem.newton_limit << "\n";
  out << "line_search_limit " << problem.line_search_limit << "\n";
  out << "failed " << problem.failed_residual << ' ' << problem.failed_iterations << "\n";
  const Box& box = problem.box;
  out << "box";
  write_vec(out, box.lo());
  write_vec(out, box.hi());
  for (int a = 0; a < 3; ++a) out << ' ' << (box.periodic(a) ? 1 : 0);
  out << "\n";
  const LocalCluster& cluster = problem.cluster;
  out << "particles " << cluster.size() << "\n# id mass q(x y z) x0(x y z)\n";
  for (std::size_t k = 0; k < cluster.size(); ++k) {
    out << problem.ids[k] << ' ' << 1.0 / cluster.inverse_mass[k];
    write_vec(out, problem.q[k]);
    write_vec(out, problem.x0[k]);
    out << "\n";
  }
  out << "rows " << cluster.rows.size()
      << "\n# kind equality|inequality i j length point(x y z) normal(x y z)\n";
  for (std::size_t r = 0; r < cluster.rows.size(); ++r) {
    const Constraint& c = cluster.rows[r];
    out << kind_word(c.kind) << (problem.equality[r] ? " equality " : " inequality ") << c.i << ' '
        << c.j << ' ' << c.length;
    write_vec(out, c.point);
    write_vec(out, c.normal);
    out << "\n";
  }
}

std::string save_position_problem(const std::string& path, const PositionProblem& problem) {
  std::ofstream out(path);
  write_position_problem(out, problem);
  out.flush();
  if (!out) return path + " could not be written (" + std::strerror(errno) + ")";
  return "is in " + path;
}

PositionProblem read_position_problem(const std::string& path) {
  ProblemReader in(path);
  PositionProblem p;
  p.step = in.integer(in.line("step", 1, "the step")[0], 0, (1LL << 62));
  p.h = in.number(in.line("h", 1, "the timestep")[0]);
  if (!(p.h > 0)) in.fail("the timestep must be positive");
  p.tolerance = in.number(in.line("tolerance", 1, "the residual tolerance")[0]);
  if (!(p.tolerance > 0)) in.fail("the tolerance must be positive");
  p.newton_limit = static_cast<int>(
      in.integer(in.line("newton_limit", 1, "the Newton iteration limit")[0], 1, 1 << 30));
  p.line_search_limit = static_cast<int>(
      in.integer(in.line("line_search_limit", 1, "the line search's halvings")[0], 1, 1 << 30));
  const auto failed = in.line("failed", 2, "the failed solve's residual and iterations");
  p.failed_residual = in.number(failed[0]);
  p.failed_iterations = static_cast<int>(in.integer(failed[1], 0, 1 << 30));
  const auto box = in.line("box", 9, "lo x y z, hi x y z, periodic 0|1 per axis");
  std::array<bool, 3> periodic{};
  for (int a = 0; a < 3; ++a) periodic[a] = in.integer(box[6 + a], 0, 1) == 1;
  p.box = Box(in.vec(box, 0), in.vec(box, 3), periodic);
  const auto n = static_cast<std::size_t>(
      in.integer(in.line("particles", 1, "the number of particles")[0], 1, 1 << 30));
  for (std::size_t k = 0; k < n; ++k) {
    const auto w = in.line("", 8, "a particle: id mass q(x y z) x0(x y z)");
    p.ids.push_back(in.integer(w[0], 0, (1LL << 62)));
    const double mass = in.number(w[1]);
    if (!(mass > 0)) in.fail("a particle's mass must be positive");
    p.cluster.particles.push_back(static_cast<std::int32_t>(k));
    p.cluster.inverse_mass.push_back(1.0 / mass);
    p.q.push_back(in.vec(w, 2));
    p.x0.push_back(in.vec(w, 5));
  }
  const auto m =
      static_cast<std::size_t>(in.integer(in.line("rows", 1, "the number of rows")[0], 1, 1 << 30));
  const auto last = static_cast<long long>(n) - 1;
  for (std::size_t r = 0; r < m; ++r) {
    const auto w = in.line("", 11, "a row: kind equality|inequality i j length point normal");
    Constraint c;
    bool known = false;
    for (const auto& [kind, word] : kKindWords) {
      if (w[0] == word) c.kind = kind, known = true;
    }
    if (!known) {
      in.fail("unknown row kind '" + w[0] +
              "' (rod, anchor, sphere_pair, plane, inside_sphere, outside_sphere, linear_pair)");
    }
    if (w[1] != "equality" && w[1] != "inequality") {
      in.fail("expected 'equality' or 'inequality', found '" + w[1] + "'");
    }
    c.i = static_cast<std::int32_t>(in.integer(w[2], 0, last));
    c.j = static_cast<std::int32_t>(
        in.integer(w[3], is_pair(c.kind) ? 0 : -1, is_pair(c.kind) ? last : -1));
    c.length = in.number(w[4]);
    c.point = in.vec(w, 5);
    c.normal = in.vec(w, 8);
    p.cluster.rows.push_back(c);
    p.cluster.global_rows.push_back(static_cast<std::int32_t>(r));
    p.equality.push_back(w[1] == "equality");
  }
  return p;
}

PositionUpdate solve_position_problem(const PositionProblem& problem, int newton_limit) {
  return solve_position_update(problem.cluster, problem.equality, problem.q, problem.x0, problem.h,
                               problem.box, problem.tolerance,
                               newton_limit > 0 ? newton_limit : problem.newton_limit,
                               problem.line_search_limit);
}

std::string describe_position_solve(const PositionProblem& problem, const PositionUpdate& solved) {
  std::ostringstream out;
  out.precision(6);
  const LocalCluster& cluster = problem.cluster;
  out << "position update of step " << problem.step << ": " << cluster.size() << " atoms, "
      << cluster.rows.size() << " rows, h " << problem.h << ", tolerance " << problem.tolerance
      << " sigma\n";
  out << (solved.status.converged ? "converged" : "NOT converged") << " after "
      << solved.status.iterations << " Newton iterations, residual " << solved.status.residual
      << " sigma";
  if (solved.line_search_failed) out << " (the line search found no step lowering the residual)";
  out << "\n(the run reported residual " << problem.failed_residual << " after "
      << problem.failed_iterations << " iterations)\n";
  out << "row  kind            held         atoms            gap (sigma)   impulse\n";
  for (std::size_t r = 0; r < cluster.rows.size(); ++r) {
    const Constraint& c = cluster.rows[r];
    std::string atoms = std::to_string(problem.ids[c.i]);
    if (c.j >= 0) atoms += " " + std::to_string(problem.ids[c.j]);
    char line[160];
    std::snprintf(line, sizeof line, "%-4zu %-15s %-12s %-16s %13.6e %13.6e\n", r,
                  kind_word(c.kind), problem.equality[r] ? "equality" : "inequality", atoms.c_str(),
                  evaluate(c, solved.x.data(), problem.box).gap,
                  solved.z(static_cast<Eigen::Index>(r)));
    out << line;
  }
  return out.str();
}

}  // namespace deli
