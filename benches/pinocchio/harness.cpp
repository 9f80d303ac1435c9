// Pinocchio side of the kanegen comparison (README "Pinocchio side by side"; run by run.sh).
//
//   harness DIR [ROUNDS CALLS]
//
// Reads DIR/cases.txt (written by `cargo run --release --example pinocchio_side_by_side -- write
// DIR`): per case a model exported by `kanegen::pinocchio` (format: codegen/src/pinocchio.rs), a
// state (q, u, u̇) in kanegen's coordinates and kanegen's generated M, c, g, τ, C for it. For each
// case it builds the pinocchio::Model (addJoint, appendBodyToJoint, armature), maps the state
// (x and ψ of the wheeled base to the planar joint, sign flips of joints about negative axes),
// runs crba, nonLinearEffects, computeGeneralizedGravity, rnea and computeCoriolisMatrix, maps
// the results back (M = Sᵀ M_pin S with the speeds' rows and columns and signs) and prints the
// largest relative differences. Then it times the five algorithms with case 0's parameters on the
// states of all cases: per algorithm ROUNDS rounds of CALLS calls cycling through the states, the
// fastest round's mean ns per call, and appends `name ns` lines to DIR/pinocchio-times.txt.
// Exit status 1 if M, c, g or τ differ by more than 1e-9 (relative to the largest entry).
//
// Header-only use of Pinocchio (no PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION): every algorithm is
// compiled here with the harness's flags (-O3 -march=native).

#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace pin = pinocchio;
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

struct Reader {
  std::istream & in;
  std::string where;

  void expect(const std::string & word) {
    std::string w;
    if (!(in >> w) || w != word)
      throw std::runtime_error(where + ": expected `" + word + "`, found `" + w + "`");
  }
  template<typename T>
  T get(const char * what) {
    T x;
    if (!(in >> x)) throw std::runtime_error(where + ": expected " + what);
    return x;
  }
  double num() { return get<double>("a number"); }
  // Three numbers in order (function arguments have no evaluation order in C++).
  Eigen::Vector3d vec3() {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = num();
    return v;
  }
  VectorXd vec(const std::string & tag, int n) {
    expect(tag);
    VectorXd v(n);
    for (int i = 0; i < n; ++i) v[i] = num();
    return v;
  }
  MatrixXd mat(const std::string & tag, int n) {
    expect(tag);
    MatrixXd m(n, n);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) m(r, c) = num();
    return m;
  }
  pin::SE3 se3() {
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r(i, j) = num();
    const Eigen::Vector3d p = vec3();
    return pin::SE3(r, p);
  }
};

enum class Coord { Joint, PlanarX, PlanarPsi };

// A kanegen model as a Pinocchio model plus the maps between the coordinates.
struct Exported {
  pin::Model model;
  int dof = 0;
  std::vector<int> v_index;   // per kanegen speed: index in Pinocchio's v
  std::vector<double> sign;   // per kanegen speed: v[v_index] = sign * u
  std::vector<Coord> coord;   // per kanegen coordinate
  std::vector<int> q_index;

  VectorXd configuration(const VectorXd & q) const {
    VectorXd out = pin::neutral(model);
    for (int i = 0; i < dof; ++i) switch (coord[i]) {
        case Coord::Joint: out[q_index[i]] = sign[i] * q[i]; break;
        case Coord::PlanarX: out[q_index[i]] = q[i]; out[q_index[i] + 1] = 0.0; break;
        case Coord::PlanarPsi:
          out[q_index[i]] = std::cos(q[i]);
          out[q_index[i] + 1] = std::sin(q[i]);
          break;
      }
    return out;
  }
  VectorXd velocity(const VectorXd & u) const {
    VectorXd out = VectorXd::Zero(model.nv);
    for (int i = 0; i < dof; ++i) out[v_index[i]] = sign[i] * u[i];
    return out;
  }
  VectorXd speeds(const VectorXd & f) const {  // Sᵀ f
    VectorXd out(dof);
    for (int i = 0; i < dof; ++i) out[i] = sign[i] * f[v_index[i]];
    return out;
  }
  MatrixXd speeds(const MatrixXd & m) const {  // Sᵀ m S
    MatrixXd out(dof, dof);
    for (int i = 0; i < dof; ++i)
      for (int j = 0; j < dof; ++j) out(i, j) = sign[i] * sign[j] * m(v_index[i], v_index[j]);
    return out;
  }
};

Exported read_model(Reader & rd) {
  Exported ex;
  rd.expect("kanegen-pinocchio");
  if (rd.get<int>("the format version") != 1)
    throw std::runtime_error(rd.where + ": unsupported format version (this harness reads 1)");
  rd.expect("model");
  ex.model.name = rd.get<std::string>("the model name");
  rd.expect("nq");
  const int nq = rd.get<int>("nq");
  rd.expect("nv");
  const int nv = rd.get<int>("nv");
  rd.expect("dof");
  ex.dof = rd.get<int>("dof");
  rd.expect("gravity");
  ex.model.gravity.linear() = rd.vec3();
  rd.expect("joints");
  const int nj = rd.get<int>("the joint count");
  for (int k = 0; k < nj; ++k) {
    rd.expect("joint");
    const auto name = rd.get<std::string>("a joint name");
    const auto parent = rd.get<pin::JointIndex>("a parent joint");
    const auto type = rd.get<std::string>("a joint type");
    const Eigen::Vector3d axis = rd.vec3();
    const pin::SE3 placement = rd.se3();
    pin::JointModel jm;
    if (type == "RX") jm = pin::JointModelRX();
    else if (type == "RY") jm = pin::JointModelRY();
    else if (type == "RZ") jm = pin::JointModelRZ();
    else if (type == "PX") jm = pin::JointModelPX();
    else if (type == "PY") jm = pin::JointModelPY();
    else if (type == "PZ") jm = pin::JointModelPZ();
    else if (type == "RU") jm = pin::JointModelRevoluteUnaligned(axis);
    else if (type == "PU") jm = pin::JointModelPrismaticUnaligned(axis);
    else if (type == "PLANAR") jm = pin::JointModelPlanar();
    else throw std::runtime_error(rd.where + ": unknown joint type `" + type + "`");
    ex.model.addJoint(parent, jm, placement, name);
  }
  rd.expect("bodies");
  const int nb = rd.get<int>("the body count");
  for (int k = 0; k < nb; ++k) {
    rd.expect("body");
    rd.get<std::string>("a body name");
    const auto joint = rd.get<pin::JointIndex>("a joint index");
    const pin::SE3 placement = rd.se3();
    const double m = rd.num();
    const Eigen::Vector3d com = rd.vec3();
    Eigen::Matrix3d ic;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) ic(i, j) = rd.num();
    ex.model.appendBodyToJoint(joint, pin::Inertia(m, com, ic), placement);
  }
  if (ex.model.nq != nq || ex.model.nv != nv)
    throw std::runtime_error(rd.where + ": the joints give nq/nv " + std::to_string(ex.model.nq) +
                             "/" + std::to_string(ex.model.nv) + ", the file says " +
                             std::to_string(nq) + "/" + std::to_string(nv));
  rd.expect("armature");
  ex.model.armature = VectorXd(nv);
  for (int i = 0; i < nv; ++i) ex.model.armature[i] = rd.num();
  rd.expect("speeds");
  rd.get<int>("the speed count");
  for (int i = 0; i < ex.dof; ++i) {
    rd.expect("speed");
    rd.get<std::string>("a speed name");
    ex.v_index.push_back(rd.get<int>("a v index"));
    ex.sign.push_back(rd.num());
  }
  rd.expect("coordinates");
  rd.get<int>("the coordinate count");
  for (int i = 0; i < ex.dof; ++i) {
    rd.expect("coordinate");
    rd.get<std::string>("a coordinate name");
    const auto kind = rd.get<std::string>("a coordinate kind");
    ex.coord.push_back(kind == "joint"      ? Coord::Joint
                       : kind == "planar_x" ? Coord::PlanarX
                       : kind == "planar_psi"
                         ? Coord::PlanarPsi
                         : throw std::runtime_error(rd.where + ": coordinate kind `" + kind + "`"));
    ex.q_index.push_back(rd.get<int>("a q index"));
    rd.num();  // the sign, equal to the speed's
  }
  rd.expect("end");
  return ex;
}

struct Case {
  Exported ex;
  VectorXd q, u, ud, c, g, tau;
  MatrixXd M, C;
};

double rel(const MatrixXd & a, const MatrixXd & b) {
  const double scale = std::max(b.cwiseAbs().maxCoeff(), 1e-300);
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

template<typename F>
double time_ns(int rounds, int calls, F && f) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rounds; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < calls; ++i) f(i);
    const auto t1 = std::chrono::steady_clock::now();
    best = std::min(best, std::chrono::duration<double, std::nano>(t1 - t0).count() / calls);
  }
  return best;
}

}  // namespace

int main(int argc, char ** argv) {
  if (argc != 2 && argc != 4) {
    std::cerr << "usage: harness DIR [ROUNDS CALLS]\n";
    return 2;
  }
  const std::string dir = argv[1];
  const int rounds = argc == 4 ? std::atoi(argv[2]) : 200;
  const int calls = argc == 4 ? std::atoi(argv[3]) : 2000;
  std::vector<Case> cases;
  try {
    const std::string path = dir + "/cases.txt";
    std::ifstream file(path);
    if (!file) throw std::runtime_error(path + ": cannot open (run the `write` step first)");
    Reader rd{file, path};
    rd.expect("cases");
    const int n = rd.get<int>("the case count");
    rd.expect("dof");
    const int dof = rd.get<int>("dof");
    for (int k = 0; k < n; ++k) {
      rd.expect("case");
      rd.where = path + ", case " + std::to_string(rd.get<int>("a case number"));
      Case c{read_model(rd)};
      c.q = rd.vec("q", dof);
      c.u = rd.vec("u", dof);
      c.ud = rd.vec("ud", dof);
      c.M = rd.mat("M", dof);
      c.c = rd.vec("c", dof);
      c.g = rd.vec("g", dof);
      c.tau = rd.vec("tau", dof);
      c.C = rd.mat("C", dof);
      cases.push_back(std::move(c));
    }
  } catch (const std::exception & e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }

  // Agreement on every case.
  double em = 0, ec = 0, eg = 0, et = 0, eC = 0, eCu = 0;
  for (auto & k : cases) {
    const Exported & ex = k.ex;
    pin::Data data(ex.model);
    const VectorXd q = ex.configuration(k.q), v = ex.velocity(k.u), a = ex.velocity(k.ud);
    pin::crba(ex.model, data, q);
    data.M.triangularView<Eigen::StrictlyLower>() =
      data.M.transpose().triangularView<Eigen::StrictlyLower>();
    const MatrixXd M = ex.speeds(MatrixXd(data.M));
    const VectorXd g = ex.speeds(VectorXd(pin::computeGeneralizedGravity(ex.model, data, q)));
    const VectorXd nle = ex.speeds(VectorXd(pin::nonLinearEffects(ex.model, data, q, v)));
    const VectorXd tau = ex.speeds(VectorXd(pin::rnea(ex.model, data, q, v, a)));
    const MatrixXd C = ex.speeds(MatrixXd(pin::computeCoriolisMatrix(ex.model, data, q, v)));
    em = std::max(em, rel(M, k.M));
    eg = std::max(eg, rel(g, k.g));
    ec = std::max(ec, rel(nle - g, k.c));
    et = std::max(et, rel(tau, k.tau));
    eC = std::max(eC, rel(C, k.C));
    eCu = std::max(eCu, rel(C * k.u, k.c));
  }
  std::printf("Pinocchio %s vs kanegen on %zu cases (random parameters and states), largest "
              "difference relative to the largest entry:\n",
              PINOCCHIO_VERSION, cases.size());
  std::printf("  M %.1e   c %.1e   g %.1e   tau %.1e   C %.1e   (Pinocchio's C u vs kanegen's c: "
              "%.1e)\n",
              em, ec, eg, et, eC, eCu);
  const bool ok = em < 1e-9 && ec < 1e-9 && eg < 1e-9 && et < 1e-9;

  // Timings with case 0's parameters on all states.
  const Exported & ex = cases[0].ex;
  pin::Data data(ex.model);
  std::vector<VectorXd> qs, vs, as;
  for (auto & k : cases) {
    qs.push_back(ex.configuration(k.q));
    vs.push_back(ex.velocity(k.u));
    as.push_back(ex.velocity(k.ud));
  }
  const size_t n = cases.size();
  double sink = 0;
  struct Row { const char * name; double ns; };
  std::vector<Row> rows = {
    {"crba", time_ns(rounds, calls, [&](int i) {
       pin::crba(ex.model, data, qs[i % n]);
       sink += data.M(0, 1);
     })},
    {"crba_world", time_ns(rounds, calls, [&](int i) {
       pin::crba(ex.model, data, qs[i % n], pin::Convention::WORLD);
       sink += data.M(0, 1);
     })},
    {"nle", time_ns(rounds, calls, [&](int i) {
       sink += pin::nonLinearEffects(ex.model, data, qs[i % n], vs[i % n])[1];
     })},
    {"gravity", time_ns(rounds, calls, [&](int i) {
       sink += pin::computeGeneralizedGravity(ex.model, data, qs[i % n])[1];
     })},
    {"rnea", time_ns(rounds, calls, [&](int i) {
       sink += pin::rnea(ex.model, data, qs[i % n], vs[i % n], as[i % n])[1];
     })},
    {"coriolis_matrix", time_ns(rounds, calls, [&](int i) {
       sink += pin::computeCoriolisMatrix(ex.model, data, qs[i % n], vs[i % n])(0, 1);
     })},
  };
  std::ofstream out(dir + "/pinocchio-times.txt", std::ios::app);
  for (const auto & r : rows) {
    std::printf("pinocchio %-18s %9.1f ns\n", r.name, r.ns);
    out << r.name << " " << r.ns << "\n";
  }
  if (sink == 12345.678) std::printf("(sink)\n");  // keeps the results alive
  if (!ok) {
    std::printf("FAILED: M, c, g or tau differ by more than 1e-9\n");
    return 1;
  }
  return 0;
}
