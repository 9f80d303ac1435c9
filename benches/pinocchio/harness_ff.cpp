// Pinocchio side of the free-flyer comparison (docs/correctness.md, docs/performance.md; run
// by run.sh).
//
//   harness_ff DIR [ROUNDS CALLS]      (default 100 2000)
//
// Reads DIR/ff-cases.txt (cases.hpp's read_ff_cases; written by `cargo run --release --example
// pinocchio_free_flyer -- write DIR`; format in that example's documentation): per case a model
// exported with a free-flyer root (`kanegen::pinocchio::export_free_flyer`), its contact frames,
// a state (q, u, u̇) in the free flyer's coordinates and the reference recursion's results. For
// each case it builds the pinocchio::Model (a JointModelFreeFlyer root, then the joints), maps
// the state (sign flips of joints about negative axes) and runs crba, nonLinearEffects,
// computeGeneralizedGravity, rnea, ccrba (Ag), computeCentroidalMomentumTimeVariation at a = 0
// (Ȧ_G v), computeRNEADerivatives and constraintDynamics with one CONTACT_3D per contact frame
// (LOCAL_WORLD_ALIGNED, mu = 0), maps the results back and prints the largest differences
// relative to the largest entry, per model. Exit status 1 if any exceeds 1e-9. Then it times,
// per model on its states (the fastest of ROUNDS rounds of CALLS calls, a tenth of them for the
// derivatives), crba, nonLinearEffects, computeGeneralizedGravity, rnea, ccrba,
// computeRNEADerivatives, aba (with the case's actuation) and constraintDynamics, and appends
// `model/algorithm ns` lines to DIR/pinocchio-ff-times.txt (`examples/pinocchio_free_flyer.rs
// report` makes the tables).

#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/centroidal.hpp>
#include <pinocchio/algorithm/constrained-dynamics.hpp>

#include <map>

#include "cases.hpp"

using namespace kanegen_cases;

struct Errors {
  double M = 0, nle = 0, g = 0, tau = 0, Ag = 0, dhg = 0, dq = 0, du = 0, cud = 0, lambda = 0;
  int cases = 0;
  double worst() const {
    return std::max({M, nle, g, tau, Ag, dhg, dq, du, cud, lambda});
  }
};

// One model's timing material: the model, its contacts and its states in Pinocchio's layout.
struct Timing {
  Exported ex;
  PINOCCHIO_STD_VECTOR_WITH_EIGEN_ALLOCATOR(pin::RigidConstraintModel) contacts;
  States states;
  std::vector<VectorXd> f;  // the actuation, in Pinocchio's v
};

// Columns of a 6 × nv Pinocchio matrix in the kanegen speeds (A S).
static MatrixXd columns(const Exported & ex, const MatrixXd & a) {
  MatrixXd out(a.rows(), ex.dof);
  for (int i = 0; i < ex.dof; ++i) out.col(i) = ex.sign[i] * a.col(ex.v_index[i]);
  return out;
}

int main(int argc, char ** argv) {
  if (argc != 2 && argc != 4) {
    std::cerr << "usage: harness_ff DIR [ROUNDS CALLS]\n";
    return 2;
  }
  const std::string dir = argv[1];
  const int rounds = argc == 4 ? std::atoi(argv[2]) : 100;
  const int calls = argc == 4 ? std::atoi(argv[3]) : 2000;
  std::vector<FfCase> cases;
  try {
    cases = read_ff_cases(dir);
  } catch (const std::exception & e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  std::map<std::string, Errors> errors;
  std::map<std::string, Timing> timing;
  for (const FfCase & k : cases) {
    const Exported & ex = k.ex;
    const int nv = ex.model.nv;
    PINOCCHIO_STD_VECTOR_WITH_EIGEN_ALLOCATOR(pin::RigidConstraintModel) contacts;
    for (const auto & [joint, placement] : k.contacts)
      contacts.push_back(pin::RigidConstraintModel(pin::CONTACT_3D, ex.model, joint, placement,
                                                   pin::LOCAL_WORLD_ALIGNED));
    pin::Data data(ex.model);
    const VectorXd q = ex.configuration(k.q), v = ex.velocity(k.u), a = ex.velocity(k.ud);
    Errors & e = errors[ex.model.name];
    e.cases += 1;
    pin::crba(ex.model, data, q);
    data.M.triangularView<Eigen::StrictlyLower>() =
      data.M.transpose().triangularView<Eigen::StrictlyLower>();
    e.M = std::max(e.M, rel(ex.speeds(MatrixXd(data.M)), k.M));
    e.nle =
      std::max(e.nle, rel(ex.speeds(VectorXd(pin::nonLinearEffects(ex.model, data, q, v))), k.nle));
    e.g = std::max(
      e.g, rel(ex.speeds(VectorXd(pin::computeGeneralizedGravity(ex.model, data, q))), k.g));
    e.tau = std::max(e.tau, rel(ex.speeds(VectorXd(pin::rnea(ex.model, data, q, v, a))), k.tau));
    e.Ag = std::max(e.Ag, rel(columns(ex, MatrixXd(pin::ccrba(ex.model, data, q, v))), k.Ag));
    const VectorXd zero = VectorXd::Zero(nv);
    const VectorXd dhg =
      pin::computeCentroidalMomentumTimeVariation(ex.model, data, q, v, zero).toVector();
    e.dhg = std::max(e.dhg, rel(dhg, k.dhg));
    pin::computeRNEADerivatives(ex.model, data, q, v, a);
    e.dq = std::max(e.dq, rel(ex.speeds(MatrixXd(data.dtau_dq)), k.dtau_dq));
    e.du = std::max(e.du, rel(ex.speeds(MatrixXd(data.dtau_dv)), k.dtau_du));
    PINOCCHIO_STD_VECTOR_WITH_EIGEN_ALLOCATOR(pin::RigidConstraintData) datas;
    for (const auto & c : contacts) datas.push_back(pin::RigidConstraintData(c));
    pin::initConstraintDynamics(ex.model, data, contacts, datas);
    pin::ProximalSettings prox(1e-12, 0.0, 1);
    const VectorXd ddq =
      pin::constraintDynamics(ex.model, data, q, v, ex.velocity(k.f), contacts, datas, prox);
    e.cud = std::max(e.cud, rel(ex.speeds(ddq), k.cud));
    e.lambda = std::max(e.lambda, rel(data.lambda_c, k.lambda));
    Timing & t = timing.try_emplace(ex.model.name, Timing{ex, contacts, {}, {}}).first->second;
    t.states.add(ex, k);
    t.f.push_back(ex.velocity(k.f));
  }
  std::printf("Pinocchio %s vs the free-flyer reference recursion (kanegen-reference) and "
              "kanegen_runtime::contact, largest difference relative to the largest entry:\n",
              PINOCCHIO_VERSION);
  bool ok = true;
  for (const auto & [name, e] : errors) {
    std::printf("  %s (%d states): M %.1e  nle %.1e  g %.1e  rnea %.1e  ccrba Ag %.1e  "
                "dAg*v %.1e  dtau/dq %.1e  dtau/dv %.1e  constraintDynamics ddq %.1e  "
                "lambda %.1e\n",
                name.c_str(), e.cases, e.M, e.nle, e.g, e.tau, e.Ag, e.dhg, e.dq, e.du, e.cud,
                e.lambda);
    ok = ok && e.worst() < 1e-9;
  }
  if (!ok) {
    std::printf("FAILED: a free-flyer result differs by more than 1e-9\n");
    return 1;
  }

  double sink = 0;
  for (auto & [name, t] : timing) {
    const pin::Model & model = t.ex.model;
    const States & s = t.states;
    pin::Data data(model);
    PINOCCHIO_STD_VECTOR_WITH_EIGEN_ALLOCATOR(pin::RigidConstraintData) datas;
    for (const auto & c : t.contacts) datas.push_back(pin::RigidConstraintData(c));
    pin::initConstraintDynamics(model, data, t.contacts, datas);
    pin::ProximalSettings prox(1e-12, 0.0, 1);
    const size_t n = s.q.size();
    append_times(dir, {
      {"crba", time_ns(rounds, calls, [&](int i) {
         pin::crba(model, data, s.q[i % n]);
         sink += data.M(0, 1);
       })},
      {"nle", time_ns(rounds, calls, [&](int i) {
         sink += pin::nonLinearEffects(model, data, s.q[i % n], s.v[i % n])[1];
       })},
      {"gravity", time_ns(rounds, calls, [&](int i) {
         sink += pin::computeGeneralizedGravity(model, data, s.q[i % n])[1];
       })},
      {"rnea", time_ns(rounds, calls, [&](int i) {
         sink += pin::rnea(model, data, s.q[i % n], s.v[i % n], s.a[i % n])[1];
       })},
      {"ccrba", time_ns(rounds, calls, [&](int i) {
         sink += pin::ccrba(model, data, s.q[i % n], s.v[i % n])(0, 1);
       })},
      {"rnea_derivatives", time_ns(rounds, calls / 10, [&](int i) {
         pin::computeRNEADerivatives(model, data, s.q[i % n], s.v[i % n], s.a[i % n]);
         sink += data.dtau_dq(5, 6) + data.dtau_dv(5, 6);
       })},
      {"aba", time_ns(rounds, calls, [&](int i) {
         sink += pin::aba(model, data, s.q[i % n], s.v[i % n], t.f[i % n])[1];
       })},
      {"constraint_dynamics", time_ns(rounds, calls, [&](int i) {
         sink += pin::constraintDynamics(model, data, s.q[i % n], s.v[i % n], t.f[i % n],
                                         t.contacts, datas, prox)[1];
         sink += data.lambda_c[0];
       })},
    }, "pinocchio-ff-times.txt", name + "/");
  }
  if (sink == 12345.678) std::printf("(sink)\n");  // keeps the results alive
  return 0;
}
