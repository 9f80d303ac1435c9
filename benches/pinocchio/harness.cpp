// Pinocchio side of the kanegen comparison (docs/performance.md; run by run.sh).
//
//   harness DIR [ROUNDS CALLS]
//
// Reads DIR/cases.txt (cases.hpp): per case a model exported by `kanegen::pinocchio`, a state
// (q, u, u̇) in kanegen's coordinates and kanegen's generated M, c, g, τ, C, ∂τ/∂q and ∂τ/∂u for
// it. For each case it builds the pinocchio::Model (addJoint, appendBodyToJoint, armature), maps
// the state (x and ψ of the wheeled base to the planar joint, sign flips of joints about negative
// axes), runs crba, nonLinearEffects, computeGeneralizedGravity, rnea, computeCoriolisMatrix and
// computeRNEADerivatives and forward dynamics (crba + nonLinearEffects reduced to the speeds,
// then Eigen's LLT), maps the results back (M = Sᵀ M_pin S with the speeds' rows and columns
// and signs) and prints the largest relative differences. Then it times the algorithms with case
// 0's parameters on the states of all cases: per algorithm ROUNDS rounds of CALLS calls cycling
// through the states, the fastest round's mean ns per call, and appends `name ns` lines to
// DIR/pinocchio-times.txt. Exit status 1 if M, c, g, τ, C (and Pinocchio's C u against kanegen's
// c), the derivatives or the forward dynamics differ by more than 1e-9 (relative to the largest
// entry).
//
// Header-only use of Pinocchio (no PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION): every algorithm is
// compiled here with the harness's flags (-O3 -march=native).

#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/aba-derivatives.hpp>

#include <Eigen/Cholesky>

#include "cases.hpp"

using namespace kanegen_cases;

// Forward dynamics of the model's speeds as a Pinocchio user computes it for Krang, whose
// wheeled base has 2 speeds (ẋ, ψ̇) where Pinocchio's planar joint has 3: crba and
// nonLinearEffects on the tree, reduced to the speeds (Sᵀ M S, Sᵀ h), then Eigen's LLT.
// Storage is allocated once.
struct ReducedForwardDynamics {
  MatrixXd m;
  VectorXd rhs, x;
  Eigen::LLT<MatrixXd> llt;
  explicit ReducedForwardDynamics(int dof) : m(dof, dof), rhs(dof), x(dof), llt(dof) {}
  const VectorXd & operator()(const Exported & ex, pin::Data & data, const VectorXd & q,
                              const VectorXd & v, const VectorXd & tau) {
    pin::crba(ex.model, data, q);  // the upper triangle of data.M
    const VectorXd & h = pin::nonLinearEffects(ex.model, data, q, v);
    for (int i = 0; i < ex.dof; ++i) {
      rhs[i] = tau[i] - ex.sign[i] * h[ex.v_index[i]];
      for (int j = 0; j <= i; ++j) {
        const int a = std::min(ex.v_index[i], ex.v_index[j]);
        const int b = std::max(ex.v_index[i], ex.v_index[j]);
        m(i, j) = ex.sign[i] * ex.sign[j] * data.M(a, b);
      }
    }
    llt.compute(m);  // reads the lower triangle
    x = llt.solve(rhs);
    return x;
  }
};

int main(int argc, char ** argv) {
  Run run;
  if (!start(argc, argv, "harness", run)) return 2;
  const std::string & dir = run.dir;
  const int rounds = run.rounds, calls = run.calls;
  const std::vector<Case> & cases = run.cases;

  // Agreement on every case.
  double em = 0, ec = 0, eg = 0, et = 0, eC = 0, eCu = 0, edq = 0, edu = 0, eda = 0;
  double efd = 0, efd_ud = 0;
  ReducedForwardDynamics fd(cases[0].ex.dof);
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
    // ∂τ/∂q in Pinocchio's tangent space: the joints' columns are d/dq (sign as for the speeds);
    // the planar joint's are zero on both sides (τ does not depend on the base's pose).
    pin::computeRNEADerivatives(ex.model, data, q, v, a);
    data.M.triangularView<Eigen::StrictlyLower>() =
      data.M.transpose().triangularView<Eigen::StrictlyLower>();
    em = std::max(em, rel(M, k.M));
    eg = std::max(eg, rel(g, k.g));
    ec = std::max(ec, rel(nle - g, k.c));
    et = std::max(et, rel(tau, k.tau));
    eC = std::max(eC, rel(C, k.C));
    eCu = std::max(eCu, rel(C * k.u, k.c));
    edq = std::max(edq, rel(ex.speeds(MatrixXd(data.dtau_dq)), k.dtau_dq));
    edu = std::max(edu, rel(ex.speeds(MatrixXd(data.dtau_dv)), k.dtau_du));
    eda = std::max(eda, rel(ex.speeds(MatrixXd(data.M)), k.M));
    // Forward dynamics of kanegen's tau for this state: kanegen's u̇ = FD(q, u, tau), and the
    // state's ud it came from.
    const VectorXd & x = fd(ex, data, q, v, k.tau);
    efd = std::max(efd, rel(x, k.fd));
    efd_ud = std::max(efd_ud, rel(x, k.ud));
  }
  std::printf("Pinocchio %s vs kanegen on %zu cases (random parameters and states), largest "
              "difference relative to the largest entry:\n",
              PINOCCHIO_VERSION, cases.size());
  std::printf("  M %.1e   c %.1e   g %.1e   tau %.1e   C %.1e   (Pinocchio's C u vs kanegen's c: "
              "%.1e)\n",
              em, ec, eg, et, eC, eCu);
  std::printf("  dtau/dq %.1e   dtau/du %.1e   (computeRNEADerivatives' dtau/da vs M: %.1e)\n",
              edq, edu, eda);
  std::printf("  forward dynamics (crba + nonLinearEffects + LLT on the speeds) vs kanegen's "
              "forward_dynamics %.1e   (vs the state's ud: %.1e)\n",
              efd, efd_ud);
  const bool ok = em < 1e-9 && ec < 1e-9 && eg < 1e-9 && et < 1e-9 && eC < 1e-9 && eCu < 1e-9
                  && edq < 1e-9 && edu < 1e-9 && efd < 1e-9;

  // Timings with case 0's parameters on all states.
  const Exported & ex = cases[0].ex;
  pin::Data data(ex.model);
  const States s(ex, cases);
  const size_t n = cases.size();
  // Each state's tau (kanegen's inverse dynamics of its ud), in the speeds and in Pinocchio's v.
  std::vector<VectorXd> tau_speeds, tau_v;
  for (const auto & k : cases) {
    tau_speeds.push_back(k.tau);
    tau_v.push_back(ex.velocity(k.tau));
  }
  double sink = 0;
  append_times(dir, {
    {"crba", time_ns(rounds, calls, [&](int i) {
       pin::crba(ex.model, data, s.q[i % n]);
       sink += data.M(0, 1);
     })},
    {"crba_world", time_ns(rounds, calls, [&](int i) {
       pin::crba(ex.model, data, s.q[i % n], pin::Convention::WORLD);
       sink += data.M(0, 1);
     })},
    {"nle", time_ns(rounds, calls, [&](int i) {
       sink += pin::nonLinearEffects(ex.model, data, s.q[i % n], s.v[i % n])[1];
     })},
    {"gravity", time_ns(rounds, calls, [&](int i) {
       sink += pin::computeGeneralizedGravity(ex.model, data, s.q[i % n])[1];
     })},
    {"rnea", time_ns(rounds, calls, [&](int i) {
       sink += pin::rnea(ex.model, data, s.q[i % n], s.v[i % n], s.a[i % n])[1];
     })},
    {"coriolis_matrix", time_ns(rounds, calls, [&](int i) {
       sink += pin::computeCoriolisMatrix(ex.model, data, s.q[i % n], s.v[i % n])(0, 1);
     })},
    {"fd_reduced", time_ns(rounds, calls, [&](int i) {
       sink += fd(ex, data, s.q[i % n], s.v[i % n], tau_speeds[i % n])[1];
     })},
    {"aba", time_ns(rounds, calls, [&](int i) {
       sink += pin::aba(ex.model, data, s.q[i % n], s.v[i % n], tau_v[i % n])[1];
     })},
    {"rnea_derivatives", time_ns(rounds, calls / 10, [&](int i) {
       pin::computeRNEADerivatives(ex.model, data, s.q[i % n], s.v[i % n], s.a[i % n]);
       sink += data.dtau_dq(5, 6) + data.dtau_dv(5, 6);
     })},
    // Forward-dynamics derivatives (∂u̇/∂q, ∂u̇/∂v, M⁻¹) by ABA's analytical derivatives, on the
    // 20-speed model like `aba` (timing only: other dynamics than kanegen's 19 speeds).
    {"aba_derivatives", time_ns(rounds, calls / 10, [&](int i) {
       pin::computeABADerivatives(ex.model, data, s.q[i % n], s.v[i % n], tau_v[i % n]);
       sink += data.ddq_dq(5, 6) + data.ddq_dv(5, 6) + data.Minv(5, 6);
     })},
  });
  if (sink == 12345.678) std::printf("(sink)\n");  // keeps the results alive
  if (!ok) {
    std::printf("FAILED: M, c, g, tau, C, the derivatives or the forward dynamics differ by more "
                "than 1e-9\n");
    return 1;
  }
  return 0;
}
