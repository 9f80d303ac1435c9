// Pinocchio's own generated code (CppADCodeGen) in the kanegen comparison (docs/performance.md;
// run by run.sh when CODEGEN=1).
//
//   codegen DIR [ROUNDS CALLS]
//
// Reads DIR/cases.txt (cases.hpp) and builds case 0's pinocchio::Model (Krang with its default
// parameters), and, when DIR/ff-cases.txt exists, each free-flyer model of it (Solo 12 and the
// humanoid, default parameters; times appended to DIR/pinocchio-ff-times.txt as
// `MODEL/cg_NAME ns`, libraries DIR/cg/cg_MODEL_NAME). For each of crba, nonLinearEffects, computeGeneralizedGravity, rnea and
// computeRNEADerivatives it records the algorithm on CppAD::AD<CppAD::cg::CG<double>> (the
// parameters become constants, as in Pinocchio's own codegen benchmarks), has CppADCodeGen write
// C source and compiles it with `$CC -O3 -march=native` into a shared library in DIR/cg (kept:
// later runs only load it; delete DIR/cg to regenerate), loads it and calls it through
// CppADCodeGen's GenericModel::ForwardZero, as Pinocchio's CodeGen classes' evalFunction does.
// It checks the generated code against Pinocchio's interpreted algorithms on the states of all
// cases (and so against kanegen, which the harness compares with the interpreted ones), times it
// like the harness and appends `cg_NAME ns` lines to DIR/pinocchio-times.txt. Exit status 1 if
// any result differs from the interpreted one by more than 1e-9 (relative to its largest entry).

#include <pinocchio/codegen/cppadcg-algo.hpp>

#include "cases.hpp"

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>

using namespace kanegen_cases;

namespace {

using Base = pin::CodeGenBase<double>;

// One algorithm recorded and compiled to a shared library: the input x, the output y.
struct Generated : Base {
  // Sets ad_Y from ad_X on the AD model and data.
  using Record = std::function<void(const ADModel &, ADData &, const ADVectorXs &, ADVectorXs &)>;

  Generated(const pin::Model & model, Eigen::Index inputs, Eigen::Index outputs,
            const std::string & name, Record record)
  : Base(model, inputs, outputs, name, "cg_" + name), record(std::move(record)) {
    build_jacobian = false;  // only the function itself, as Pinocchio's CRBA and derivative ones
  }

  void buildMap() override {
    CppAD::Independent(ad_X);
    record(ad_model, ad_data, ad_X, ad_Y);
    ad_fun.Dependent(ad_X, ad_Y);
    ad_fun.optimize("no_compare_op");
  }

  // Generates and compiles the library unless DIR/cg holds it already, then loads it.
  void compile_and_load(const std::string & cc) {
    initLib();
    if (!existLib()) {
      std::printf("codegen: compiling %s (%s -O3 -march=native)\n", function_name.c_str(),
                  cc.c_str());
      std::fflush(stdout);
      CppAD::cg::GccCompiler<double> compiler(cc);
      compiler.setCompileFlags({"-O3", "-march=native"});
      dynamicLibManager_ptr->createDynamicLibrary(compiler, false);
    }
    loadLib(false);
  }

  const VectorXs & eval(const VectorXd & x) {
    evalFunction(x);
    return y;
  }

  Record record;
};

// Records, compiles (or loads), checks and times crba, nonLinearEffects,
// computeGeneralizedGravity, rnea and computeRNEADerivatives of `ex` on the states `s`: libraries
// DIR/cg/cg_LIBncrba…, times appended to DIR/FILE as `KEYcg_crba ns` …. False if a result
// differs from Pinocchio's interpreted algorithm by more than 1e-9; throws if a library cannot
// be built.
bool generate_check_time(const Exported & ex, const States & s, const std::string & lib,
                         const std::string & dir, const std::string & file,
                         const std::string & key, const std::string & cc, int rounds, int calls) {
  const pin::Model & model = ex.model;
  const Eigen::Index nq = model.nq, nv = model.nv;
  using ADVectorXs = Base::ADVectorXs;
  using ADModel = Base::ADModel;
  using ADData = Base::ADData;
  using ADMatrixXs = ADData::MatrixXs;
  using RowADMatrixXs = Eigen::Matrix<Base::ADScalar, Eigen::Dynamic, Eigen::Dynamic,
                                      Eigen::RowMajor>;

  Generated crba(model, nq, nv * (nv + 1) / 2, lib + "crba",
                 [](const ADModel & m, ADData & d, const ADVectorXs & x, ADVectorXs & y) {
                   pin::crba(m, d, x, pin::Convention::WORLD);
                   Eigen::Index k = 0;
                   for (Eigen::Index i = 0; i < m.nv; ++i)
                     for (Eigen::Index j = i; j < m.nv; ++j) y[k++] = d.M(i, j);
                 });
  Generated nle(model, nq + nv, nv, lib + "nle",
                [](const ADModel & m, ADData & d, const ADVectorXs & x, ADVectorXs & y) {
                  y = pin::nonLinearEffects(m, d, x.head(m.nq), x.tail(m.nv));
                });
  Generated gravity(model, nq, nv, lib + "gravity",
                    [](const ADModel & m, ADData & d, const ADVectorXs & x, ADVectorXs & y) {
                      y = pin::computeGeneralizedGravity(m, d, x);
                    });
  Generated rnea(model, nq + 2 * nv, nv, lib + "rnea",
                 [](const ADModel & m, ADData & d, const ADVectorXs & x, ADVectorXs & y) {
                   y = pin::rnea(m, d, x.head(m.nq), x.segment(m.nq, m.nv), x.tail(m.nv));
                 });
  // Pinocchio's CodeGenRNEADerivatives: ∂τ/∂q, ∂τ/∂v, ∂τ/∂a (= M) row-major, one after another.
  Generated derivatives(
    model, nq + 2 * nv, 3 * nv * nv, lib + "rnea_derivatives",
    [](const ADModel & m, ADData & d, const ADVectorXs & x, ADVectorXs & y) {
      ADMatrixXs dq = ADMatrixXs::Zero(m.nv, m.nv), dv = dq, da = dq;
      pin::computeRNEADerivatives(m, d, x.head(m.nq), x.segment(m.nq, m.nv), x.tail(m.nv), dq,
                                  dv, da);
      const Eigen::Index n2 = m.nv * m.nv;
      Eigen::Map<RowADMatrixXs>(y.data(), m.nv, m.nv) = dq;
      Eigen::Map<RowADMatrixXs>(y.data() + n2, m.nv, m.nv) = dv;
      Eigen::Map<RowADMatrixXs>(y.data() + 2 * n2, m.nv, m.nv) = da;
    });
  for (Generated * g : {&crba, &nle, &gravity, &rnea, &derivatives}) g->compile_and_load(cc);

  // Inputs per state: q; [q, v]; [q, v, a].
  const size_t n = s.q.size();
  std::vector<VectorXd> xq(n), xqv(n), xqva(n);
  for (size_t i = 0; i < n; ++i) {
    xq[i] = s.q[i];
    xqv[i] = VectorXd(nq + nv);
    xqv[i] << s.q[i], s.v[i];
    xqva[i] = VectorXd(nq + 2 * nv);
    xqva[i] << s.q[i], s.v[i], s.a[i];
  }

  // Agreement with the interpreted algorithms on every state.
  pin::Data data(model);
  double em = 0, ec = 0, eg = 0, et = 0, ed = 0;
  for (size_t i = 0; i < n; ++i) {
    pin::crba(model, data, s.q[i], pin::Convention::WORLD);
    MatrixXd M = MatrixXd::Zero(nv, nv);
    const VectorXd & ym = crba.eval(xq[i]);
    Eigen::Index k = 0;
    for (Eigen::Index r = 0; r < nv; ++r)
      for (Eigen::Index c = r; c < nv; ++c) M(r, c) = ym[k++];
    em = std::max(em, rel(M, MatrixXd(data.M.triangularView<Eigen::Upper>())));
    ec = std::max(ec, rel(nle.eval(xqv[i]), pin::nonLinearEffects(model, data, s.q[i], s.v[i])));
    eg = std::max(eg, rel(gravity.eval(xq[i]), pin::computeGeneralizedGravity(model, data, s.q[i])));
    et = std::max(et, rel(rnea.eval(xqva[i]), pin::rnea(model, data, s.q[i], s.v[i], s.a[i])));
    pin::computeRNEADerivatives(model, data, s.q[i], s.v[i], s.a[i]);
    const VectorXd & yd = derivatives.eval(xqva[i]);
    using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const Eigen::Index n2 = nv * nv;
    ed = std::max(ed, rel(Eigen::Map<const RowMatrixXd>(yd.data(), nv, nv), data.dtau_dq));
    ed = std::max(ed, rel(Eigen::Map<const RowMatrixXd>(yd.data() + n2, nv, nv), data.dtau_dv));
  }
  std::printf("%s: Pinocchio's generated code vs its algorithms on %zu states: M %.1e   nle %.1e   "
              "g %.1e   tau %.1e   dtau/dq, dtau/dv %.1e\n",
              model.name.c_str(), n, em, ec, eg, et, ed);

  double sink = 0;
  append_times(dir, {
    {"cg_crba", time_ns(rounds, calls, [&](int i) { sink += crba.eval(xq[i % n])[1]; })},
    {"cg_nle", time_ns(rounds, calls, [&](int i) { sink += nle.eval(xqv[i % n])[1]; })},
    {"cg_gravity", time_ns(rounds, calls, [&](int i) { sink += gravity.eval(xq[i % n])[1]; })},
    {"cg_rnea", time_ns(rounds, calls, [&](int i) { sink += rnea.eval(xqva[i % n])[1]; })},
    {"cg_rnea_derivatives",
     time_ns(rounds, calls / 10, [&](int i) { sink += derivatives.eval(xqva[i % n])[25]; })},
  }, file, key);
  if (sink == 12345.678) std::printf("(sink)\n");  // keeps the results alive
  return em < 1e-9 && ec < 1e-9 && eg < 1e-9 && et < 1e-9 && ed < 1e-9;
}

}  // namespace

int main(int argc, char ** argv) {
  Run run;
  if (!start(argc, argv, "codegen", run)) return 2;
  // Absolute: the libraries are built and loaded from DIR/cg, made the working directory below.
  const std::string dir = std::filesystem::absolute(run.dir).string();
  const char * cc_env = std::getenv("CC");
  const std::string cc = cc_env && *cc_env ? cc_env : "/usr/bin/gcc";
  const std::string lib_dir = dir + "/cg";
  bool ok = true;
  try {
    // Free-flyer models (DIR/ff-cases.txt, when the free-flyer step wrote it): the first case's
    // model of each, on all its states.
    std::vector<FfCase> ff;
    if (std::filesystem::exists(dir + "/ff-cases.txt")) ff = read_ff_cases(dir);
    std::filesystem::create_directories(lib_dir);
    std::filesystem::current_path(lib_dir);  // CppADCodeGen writes and loads the libraries here
    // Krang: case 0's parameters on the states of all cases.
    const Exported & ex = run.cases[0].ex;
    ok = generate_check_time(ex, States(ex, run.cases), "", dir, "pinocchio-times.txt", "", cc,
                             run.rounds, run.calls);
    std::map<std::string, std::pair<const Exported *, States>> models;
    for (const FfCase & k : ff) {
      auto & [model, states] = models.try_emplace(k.ex.model.name, &k.ex, States()).first->second;
      states.add(*model, k);
    }
    for (const auto & [name, m] : models)
      ok = generate_check_time(*m.first, m.second, name + "_", dir, "pinocchio-ff-times.txt",
                               name + "/", cc, run.rounds, run.calls) &&
           ok;
  } catch (const std::exception & e) {
    std::cerr << "error: " << lib_dir << ": " << e.what() << "\n";
    return 2;
  }
  if (!ok) {
    std::printf("FAILED: Pinocchio's generated code differs from its algorithms by more than 1e-9\n");
    return 1;
  }
  return 0;
}
