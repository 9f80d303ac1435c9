// Pinocchio side of the free-flyer comparison (docs/correctness.md; run by run.sh).
//
//   harness_ff DIR
//
// Reads DIR/ff-cases.txt (written by `cargo run --release --example pinocchio_free_flyer --
// DIR`; format in that example's documentation): per case a model exported with a free-flyer
// root (`kanegen::pinocchio::export_free_flyer`), its contact frames, a state (q, u, u̇) in the
// free flyer's coordinates and the reference recursion's results. For each case it builds the
// pinocchio::Model (a JointModelFreeFlyer root, then the joints), maps the state (sign flips of
// joints about negative axes) and runs crba, nonLinearEffects, computeGeneralizedGravity, rnea,
// ccrba (Ag), computeCentroidalMomentumTimeVariation at a = 0 (Ȧ_G v), computeRNEADerivatives
// and constraintDynamics with one CONTACT_3D per contact frame (LOCAL_WORLD_ALIGNED, mu = 0),
// maps the results back and prints the largest differences relative to the largest entry, per
// model. Exit status 1 if any exceeds 1e-9. Then it times, per model on its states (the fastest
// of ROUNDS rounds of CALLS calls, a tenth of them for the derivatives), crba,
// nonLinearEffects, computeGeneralizedGravity, rnea, ccrba, computeRNEADerivatives, aba (with
// the case's actuation) and constraintDynamics, and appends `model/algorithm ns` lines to
// DIR/pinocchio-ff-times.txt (`examples/pinocchio_free_flyer.rs report` makes the tables).
//
//   harness_ff DIR [ROUNDS CALLS]      (default 100 2000)

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
  std::vector<VectorXd> q, v, a, f;
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
  const int rounds = argc == 4 ? std::atoi(argv[2]) : 100;
  const int calls = argc == 4 ? std::atoi(argv[3]) : 2000;
  const std::string path = std::string(argv[1]) + "/ff-cases.txt";
  std::ifstream file(path);
  if (!file) {
    std::cerr << "error: " << path << ": cannot open (run the pinocchio_free_flyer step first)\n";
    return 2;
  }
  std::map<std::string, Errors> errors;
  std::map<std::string, Timing> timing;
  try {
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
      const Exported ex = read_model(rd);
      PINOCCHIO_STD_VECTOR_WITH_EIGEN_ALLOCATOR(pin::RigidConstraintModel) contacts;
      for (int c = 0; c < nc; ++c) {
        rd.expect("contact");
        rd.get<std::string>("a frame name");
        const auto joint = rd.get<pin::JointIndex>("a joint index");
        const pin::SE3 placement = rd.se3();
        contacts.push_back(pin::RigidConstraintModel(pin::CONTACT_3D, ex.model, joint, placement,
                                                     pin::LOCAL_WORLD_ALIGNED));
      }
      const VectorXd kq = rd.vec("q", nq), ku = rd.vec("u", nv), kud = rd.vec("ud", nv);
      const MatrixXd kM = rd.mat("M", nv);
      const VectorXd knle = rd.vec("nle", nv), kg = rd.vec("g", nv), ktau = rd.vec("tau", nv);
      rd.expect("Ag");
      MatrixXd kAg(6, nv);
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < nv; ++c) kAg(r, c) = rd.num();
      const VectorXd kdhg = rd.vec("dhg", 6);
      const MatrixXd kdq = rd.mat("dtau_dq", nv), kdu = rd.mat("dtau_du", nv);
      const VectorXd kf = rd.vec("f", nv), kcud = rd.vec("cud", nv);
      const VectorXd klambda = rd.vec("lambda", 3 * nc);

      pin::Data data(ex.model);
      const VectorXd q = ex.configuration(kq), v = ex.velocity(ku), a = ex.velocity(kud);
      Errors & e = errors[ex.model.name];
      e.cases += 1;
      pin::crba(ex.model, data, q);
      data.M.triangularView<Eigen::StrictlyLower>() =
        data.M.transpose().triangularView<Eigen::StrictlyLower>();
      e.M = std::max(e.M, rel(ex.speeds(MatrixXd(data.M)), kM));
      e.nle = std::max(
        e.nle, rel(ex.speeds(VectorXd(pin::nonLinearEffects(ex.model, data, q, v))), knle));
      e.g = std::max(
        e.g, rel(ex.speeds(VectorXd(pin::computeGeneralizedGravity(ex.model, data, q))), kg));
      e.tau = std::max(e.tau, rel(ex.speeds(VectorXd(pin::rnea(ex.model, data, q, v, a))), ktau));
      e.Ag = std::max(e.Ag, rel(columns(ex, MatrixXd(pin::ccrba(ex.model, data, q, v))), kAg));
      const VectorXd zero = VectorXd::Zero(ex.model.nv);
      const VectorXd dhg =
        pin::computeCentroidalMomentumTimeVariation(ex.model, data, q, v, zero).toVector();
      e.dhg = std::max(e.dhg, rel(dhg, kdhg));
      pin::computeRNEADerivatives(ex.model, data, q, v, a);
      e.dq = std::max(e.dq, rel(ex.speeds(MatrixXd(data.dtau_dq)), kdq));
      e.du = std::max(e.du, rel(ex.speeds(MatrixXd(data.dtau_dv)), kdu));
      PINOCCHIO_STD_VECTOR_WITH_EIGEN_ALLOCATOR(pin::RigidConstraintData) datas;
      for (const auto & c : contacts) datas.push_back(pin::RigidConstraintData(c));
      pin::initConstraintDynamics(ex.model, data, contacts, datas);
      pin::ProximalSettings prox(1e-12, 0.0, 1);
      const VectorXd ddq = pin::constraintDynamics(ex.model, data, q, v, ex.velocity(kf),
                                                   contacts, datas, prox);
      e.cud = std::max(e.cud, rel(ex.speeds(ddq), kcud));
      e.lambda = std::max(e.lambda, rel(data.lambda_c, klambda));
      Timing & t = timing.try_emplace(ex.model.name, Timing{ex, contacts, {}, {}, {}, {}})
                     .first->second;
      t.q.push_back(q);
      t.v.push_back(v);
      t.a.push_back(a);
      t.f.push_back(ex.velocity(kf));
    }
  } catch (const std::exception & ex) {
    std::cerr << "error: " << ex.what() << "\n";
    return 2;
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

  std::ofstream out(std::string(argv[1]) + "/pinocchio-ff-times.txt", std::ios::app);
  double sink = 0;
  for (auto & [name, t] : timing) {
    const pin::Model & model = t.ex.model;
    pin::Data data(model);
    PINOCCHIO_STD_VECTOR_WITH_EIGEN_ALLOCATOR(pin::RigidConstraintData) datas;
    for (const auto & c : t.contacts) datas.push_back(pin::RigidConstraintData(c));
    pin::initConstraintDynamics(model, data, t.contacts, datas);
    pin::ProximalSettings prox(1e-12, 0.0, 1);
    const size_t n = t.q.size();
    const std::vector<Row> rows = {
      {"crba", time_ns(rounds, calls, [&](int i) {
         pin::crba(model, data, t.q[i % n]);
         sink += data.M(0, 1);
       })},
      {"nle", time_ns(rounds, calls, [&](int i) {
         sink += pin::nonLinearEffects(model, data, t.q[i % n], t.v[i % n])[1];
       })},
      {"gravity", time_ns(rounds, calls, [&](int i) {
         sink += pin::computeGeneralizedGravity(model, data, t.q[i % n])[1];
       })},
      {"rnea", time_ns(rounds, calls, [&](int i) {
         sink += pin::rnea(model, data, t.q[i % n], t.v[i % n], t.a[i % n])[1];
       })},
      {"ccrba", time_ns(rounds, calls, [&](int i) {
         sink += pin::ccrba(model, data, t.q[i % n], t.v[i % n])(0, 1);
       })},
      {"rnea_derivatives", time_ns(rounds, calls / 10, [&](int i) {
         pin::computeRNEADerivatives(model, data, t.q[i % n], t.v[i % n], t.a[i % n]);
         sink += data.dtau_dq(5, 6) + data.dtau_dv(5, 6);
       })},
      {"aba", time_ns(rounds, calls, [&](int i) {
         sink += pin::aba(model, data, t.q[i % n], t.v[i % n], t.f[i % n])[1];
       })},
      {"constraint_dynamics", time_ns(rounds, calls, [&](int i) {
         sink += pin::constraintDynamics(model, data, t.q[i % n], t.v[i % n], t.f[i % n],
                                         t.contacts, datas, prox)[1];
         sink += data.lambda_c[0];
       })},
    };
    for (const auto & r : rows) {
      std::printf("pinocchio %s/%-20s %9.1f ns\n", name.c_str(), r.name, r.ns);
      out << name << "/" << r.name << " " << r.ns << "\n";
    }
  }
  if (sink == 12345.678) std::printf("(sink)\n");  // keeps the results alive
  return 0;
}
