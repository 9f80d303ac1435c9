// Shared by the Pinocchio harnesses (harness.cpp, harness_ff.cpp, codegen.cpp;
// docs/performance.md): reading DIR/cases.txt (written by `cargo run --release --example
// pinocchio_side_by_side -- write DIR`; format in that example's documentation) and
// DIR/ff-cases.txt (the free-flyer models, `--example pinocchio_free_flyer -- write DIR`),
// building each case's pinocchio::Model, the maps between kanegen's and Pinocchio's
// coordinates, and the timing loop.
//
// Include it after Pinocchio's own headers (codegen.cpp includes CppADCodeGen's first).

#pragma once

#include <pinocchio/multibody.hpp>

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

namespace kanegen_cases {

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
  std::vector<Coord> coord;   // per kanegen coordinate (dof, or dof + 1 with a free flyer)
  std::vector<int> q_index;
  std::vector<double> q_sign;  // per kanegen coordinate: q_pin[q_index] = q_sign * q

  VectorXd configuration(const VectorXd & q) const {
    VectorXd out = pin::neutral(model);
    for (int i = 0; i < int(coord.size()); ++i) switch (coord[i]) {
        case Coord::Joint: out[q_index[i]] = q_sign[i] * q[i]; break;
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

inline Exported read_model(Reader & rd) {
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
    else if (type == "FREEFLYER") jm = pin::JointModelFreeFlyer();
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
  // dof, or dof + 1 with a free-flyer root (its quaternion).
  const int ncoord = rd.get<int>("the coordinate count");
  for (int i = 0; i < ncoord; ++i) {
    rd.expect("coordinate");
    rd.get<std::string>("a coordinate name");
    const auto kind = rd.get<std::string>("a coordinate kind");
    ex.coord.push_back(kind == "joint"      ? Coord::Joint
                       : kind == "planar_x" ? Coord::PlanarX
                       : kind == "planar_psi"
                         ? Coord::PlanarPsi
                         : throw std::runtime_error(rd.where + ": coordinate kind `" + kind + "`"));
    ex.q_index.push_back(rd.get<int>("a q index"));
    ex.q_sign.push_back(rd.num());
  }
  rd.expect("end");
  return ex;
}

// One case of cases.txt: a parameter set's model, a state and kanegen's results for them
// (dtau_dq, dtau_du: the generated `inverse_dynamics_derivatives`; fd: `forward_dynamics` of
// that state's tau, which returns ud up to round-off).
struct Case {
  Exported ex;
  VectorXd q, u, ud, c, g, tau, fd;
  MatrixXd M, C, dtau_dq, dtau_du;
};

// Reads DIR/cases.txt; throws std::runtime_error naming the file, the case and what was expected.
inline std::vector<Case> read_cases(const std::string & dir) {
  std::vector<Case> cases;
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
    c.dtau_dq = rd.mat("dtau_dq", dof);
    c.dtau_du = rd.mat("dtau_du", dof);
    c.fd = rd.vec("fd", dof);
    cases.push_back(std::move(c));
  }
  if (cases.empty()) throw std::runtime_error(path + ": no cases");
  return cases;
}

// One case of ff-cases.txt: a free-flyer model, its contact frames (parent joint, placement), a
// state in kanegen's coordinates and the free-flyer reference recursion's results for it.
struct FfCase {
  Exported ex;
  std::vector<std::pair<pin::JointIndex, pin::SE3>> contacts;
  VectorXd q, u, ud, nle, g, tau, dhg, f, cud, lambda;
  MatrixXd M, Ag, dtau_dq, dtau_du;
};

// Reads DIR/ff-cases.txt; throws std::runtime_error naming the file, the case and what was
// expected.
inline std::vector<FfCase> read_ff_cases(const std::string & dir) {
  std::vector<FfCase> cases;
  const std::string path = dir + "/ff-cases.txt";
  std::ifstream file(path);
  if (!file)
    throw std::runtime_error(path + ": cannot open (run the pinocchio_free_flyer `write` step first)");
  Reader rd{file, path};
  rd.expect("ff-cases");
  const int n = rd.get<int>("the case count");
  for (int k = 0; k < n; ++k) {
    rd.expect("ff-case");
    rd.where = path + ", case " + std::to_string(rd.get<int>("a case number"));
    rd.expect("nq");
    const int nq = rd.get<int>("nq");
    rd.expect("nv");
    const int nv = rd.get<int>("nv");
    rd.expect("contacts");
    const int nc = rd.get<int>("the contact count");
    FfCase c{read_model(rd)};
    for (int i = 0; i < nc; ++i) {
      rd.expect("contact");
      rd.get<std::string>("a frame name");
      const auto joint = rd.get<pin::JointIndex>("a joint index");
      c.contacts.emplace_back(joint, rd.se3());
    }
    c.q = rd.vec("q", nq);
    c.u = rd.vec("u", nv);
    c.ud = rd.vec("ud", nv);
    c.M = rd.mat("M", nv);
    c.nle = rd.vec("nle", nv);
    c.g = rd.vec("g", nv);
    c.tau = rd.vec("tau", nv);
    rd.expect("Ag");
    c.Ag = MatrixXd(6, nv);
    for (int r = 0; r < 6; ++r)
      for (int col = 0; col < nv; ++col) c.Ag(r, col) = rd.num();
    c.dhg = rd.vec("dhg", 6);
    c.dtau_dq = rd.mat("dtau_dq", nv);
    c.dtau_du = rd.mat("dtau_du", nv);
    c.f = rd.vec("f", nv);
    c.cud = rd.vec("cud", nv);
    c.lambda = rd.vec("lambda", 3 * nc);
    cases.push_back(std::move(c));
  }
  if (cases.empty()) throw std::runtime_error(path + ": no cases");
  return cases;
}

// A harness's command line `NAME DIR [ROUNDS CALLS]` and the cases of DIR/cases.txt.
struct Run {
  std::string dir;
  int rounds = 200;  // timing rounds per algorithm (the fastest counts)
  int calls = 2000;  // calls per round
  std::vector<Case> cases;
};

// Parses the command line and reads the cases; prints the usage or the error and returns false
// (the harness then exits with status 2).
inline bool start(int argc, char ** argv, const char * name, Run & run) {
  if (argc != 2 && argc != 4) {
    std::cerr << "usage: " << name << " DIR [ROUNDS CALLS]\n";
    return false;
  }
  run.dir = argv[1];
  if (argc == 4) {
    run.rounds = std::atoi(argv[2]);
    run.calls = std::atoi(argv[3]);
  }
  try {
    run.cases = read_cases(run.dir);
  } catch (const std::exception & e) {
    std::cerr << "error: " << e.what() << "\n";
    return false;
  }
  return true;
}

// Pinocchio's configurations, velocities and accelerations of every case's state (cases of
// cases.txt or ff-cases.txt: anything with q, u and ud).
struct States {
  std::vector<VectorXd> q, v, a;
  States() = default;
  template<typename C>
  explicit States(const Exported & ex, const std::vector<C> & cases) {
    for (const auto & k : cases) add(ex, k);
  }
  template<typename C>
  void add(const Exported & ex, const C & k) {
    q.push_back(ex.configuration(k.q));
    v.push_back(ex.velocity(k.u));
    a.push_back(ex.velocity(k.ud));
  }
};

// Largest difference relative to the largest entry of b.
inline double rel(const MatrixXd & a, const MatrixXd & b) {
  const double scale = std::max(b.cwiseAbs().maxCoeff(), 1e-300);
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

// The fastest of `rounds` rounds of `calls` calls f(0), f(1), …: mean ns per call.
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

// One timed algorithm: its name in the times file and ns per call.
struct Row {
  const char * name;
  double ns;
};

// Prints the rows and appends `PREFIXname ns` lines to DIR/FILE (default
// DIR/pinocchio-times.txt, no prefix).
inline void append_times(const std::string & dir, const std::vector<Row> & rows,
                         const std::string & file = "pinocchio-times.txt",
                         const std::string & prefix = "") {
  std::ofstream out(dir + "/" + file, std::ios::app);
  for (const auto & r : rows) {
    std::printf("pinocchio %s%-22s %9.1f ns\n", prefix.c_str(), r.name, r.ns);
    out << prefix << r.name << " " << r.ns << "\n";
  }
}

}  // namespace kanegen_cases
