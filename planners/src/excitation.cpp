#include "csp/planners/excitation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

#include <nlopt.hpp>

#include "csp/dynamics/algorithms.hpp"

namespace csp::planners {

namespace {

constexpr int kState = 3 * kNumJoints;        // (q, dq, ddq)
constexpr double kStep = 1e-6;                // forward-difference step in the state
constexpr double kClearanceScale = 0.05;      // [m]: clearance margins are normalised by 5 cm
using StateRow = Eigen::Matrix<double, 1, kState>;

// Constraint groups, in margins() order.
enum Group { kPosition, kVelocity, kAcceleration, kJerk, kTorque, kGroups };
const char* const kGroupNames[kGroups] = {"q", "dq", "ddq", "dddq", "tau"};

JointSample perturbed(const JointSample& s, int i, double h) {
  JointSample out = s;
  if (i < kNumJoints) out.q[i] += h;
  else if (i < 2 * kNumJoints) out.dq[i - kNumJoints] += h;
  else out.ddq[i - 2 * kNumJoints] += h;
  return out;
}

// Smooth minimum -(1/rho) log sum exp(-rho m_n) (<= min m_n) and its gradient.
struct SmoothMin {
  std::vector<double> values;
  std::vector<Eigen::VectorXd> gradients;
  void add(double value, Eigen::VectorXd gradient) {
    values.push_back(value);
    gradients.push_back(std::move(gradient));
  }
  double evaluate(double rho, Eigen::VectorXd* gradient) const {
    const double lowest = *std::min_element(values.begin(), values.end());
    double sum = 0.0;
    for (double v : values) sum += std::exp(-rho * (v - lowest));
    if (gradient && !gradients.empty()) {
      gradient->setZero(gradients.front().size());
      for (std::size_t n = 0; n < values.size(); ++n) *gradient += std::exp(-rho * (values[n] - lowest)) / sum * gradients[n];
    }
    return lowest - std::log(sum) / rho;
  }
};

}  // namespace

bool LimitUsage::within() const {
  for (const Vector7* v : {&q, &dq, &ddq, &dddq, &tau, &dtau})
    if (!(v->maxCoeff() <= 1.0)) return false;
  return power <= 1.0 && tool_speed <= 1.0 && min_clearance >= 0.0;
}

std::string LimitUsage::worst() const {
  std::ostringstream out;
  double worst = -INFINITY;
  const std::pair<const char*, const Vector7*> vectors[] = {{"q", &q}, {"dq", &dq}, {"ddq", &ddq}, {"dddq", &dddq}, {"tau", &tau}, {"dtau", &dtau}};
  for (const auto& [name, v] : vectors) {
    Eigen::Index j;
    const double value = v->maxCoeff(&j);
    if (value > worst) {
      worst = value;
      out.str("");
      out << name << " joint " << j + 1 << ": " << value;
    }
  }
  if (power > worst) {
    worst = power;
    out.str("");
    out << "power: " << power;
  }
  if (tool_speed > worst) {
    out.str("");
    out << "tool speed: " << tool_speed;
  }
  if (min_clearance < 0.0) out << "; clearance " << min_clearance << " m";
  return out.str();
}

ExcitationProblem::ExcitationProblem(const Model& model, ExcitationOptions options)
    : model_(model), options_(std::move(options)), id_(model) {
  const ExcitationOptions& o = options_;
  const ExcitationLimits& l = o.limits;
  if (o.harmonics < 2) throw std::invalid_argument("excitation: harmonics must be >= 2 (rest to rest needs 3 conditions)");
  if (!(o.fundamental_hz > 0.0) || !(o.design_rate_hz > 2.0 * o.harmonics * o.fundamental_hz))
    throw std::invalid_argument("excitation: fundamental_hz must be > 0 and design_rate_hz above twice the top harmonic");
  if (o.periods < 1) throw std::invalid_argument("excitation: periods must be >= 1");
  if (o.random_starts < 1) throw std::invalid_argument("excitation: random_starts must be >= 1");
  if (!(o.task_weight >= 0.0)) throw std::invalid_argument("excitation: task_weight must be >= 0");
  for (double f : {l.dq, l.ddq, l.dddq, l.tau})
    if (!(f > 0.0 && f <= 1.0)) throw std::invalid_argument("excitation: limit fractions must be in (0, 1]");
  if (!(l.dtau > 0.0 && l.power > 0.0 && l.tool_speed > 0.0 && l.position_margin >= 0.0))
    throw std::invalid_argument("excitation: dtau, power and tool_speed limits must be > 0, the position margin >= 0");
  const JointLimits& limits = model_.parameters().joint_limits;
  for (int j = 0; j < kNumJoints; ++j)
    if (!(o.anchor[j] > limits.q_min[j] + l.position_margin && o.anchor[j] < limits.q_max[j] - l.position_margin))
      throw std::invalid_argument("excitation: anchor joint " + std::to_string(j + 1) + " is not inside its limits by the " +
                                  "position margin");
  if (o.prior_information.size() > 0 &&
      (o.prior_information.rows() != id_.parameters() || o.prior_information.cols() != id_.parameters()))
    throw std::invalid_argument("excitation: prior_information must be " + std::to_string(id_.parameters()) + " x " +
                                std::to_string(id_.parameters()));
  if (o.clearance && !(o.clearance(o.anchor) > 0.0))
    throw std::invalid_argument("excitation: the anchor is in collision (clearance <= 0)");

  if (!o.task.empty()) {
    const Eigen::MatrixXd task = id_.stacked_scaled(o.task);
    task_information_ = task.transpose() * task;
    task_rows_ = static_cast<int>(task.rows());
  }

  const Eigen::MatrixXd basis = rest_to_rest_basis(o.harmonics);
  const int n = o.harmonics, samples = static_cast<int>(std::lround(o.design_rate_hz / o.fundamental_hz));
  const double omega = 2.0 * std::numbers::pi * o.fundamental_hz;
  design_q_.resize(samples, basis.cols());
  design_dq_.resizeLike(design_q_);
  design_ddq_.resizeLike(design_q_);
  design_dddq_.resizeLike(design_q_);
  for (int k = 0; k < samples; ++k) {
    const double t = k / (o.fundamental_hz * samples);
    Eigen::VectorXd q(2 * n), dq(2 * n), ddq(2 * n), dddq(2 * n);   // phi(t) for (a_1..a_N, b_1..b_N)
    for (int i = 1; i <= n; ++i) {
      const double w = omega * i, c = std::cos(w * t), s = std::sin(w * t);
      q[i - 1] = s / w, q[n + i - 1] = (1.0 - c) / w;
      dq[i - 1] = c, dq[n + i - 1] = s;
      ddq[i - 1] = -w * s, ddq[n + i - 1] = w * c;
      dddq[i - 1] = -w * w * c, dddq[n + i - 1] = -w * w * s;
    }
    design_q_.row(k) = basis.transpose() * q;
    design_dq_.row(k) = basis.transpose() * dq;
    design_ddq_.row(k) = basis.transpose() * ddq;
    design_dddq_.row(k) = basis.transpose() * dddq;
  }
  if (!(model_.parameters().joint_limits.tau_max.array() > 0.0).all())
    throw std::invalid_argument("excitation: the model has no torque limits");
  Data data;
  Vector7 g;
  gravity_torque(model_, data, o.anchor, g);
  if (!((g.cwiseAbs().array() < l.tau * limits.tau_max.array()).all()))
    throw std::invalid_argument("excitation: gravity at the anchor is above the torque fraction of the limits");
}

FourierSeries ExcitationProblem::series(const std::vector<double>& x) const {
  const int m = 2 * options_.harmonics - 3;
  if (static_cast<int>(x.size()) != kNumJoints * m) throw std::invalid_argument("excitation: wrong number of coefficients");
  const Eigen::MatrixXd free = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(x.data(), kNumJoints, m);
  return FourierSeries::rest_to_rest(options_.fundamental_hz, options_.harmonics, free, options_.anchor);
}

Criterion ExcitationProblem::design_value(const Eigen::MatrixXd& A, double lambda) const {
  if (options_.design == ExcitationOptions::Design::kConditionNumber) return condition_criterion(A);
  return design_criterion(A, task_information_, task_rows_, lambda);
}

JointSample ExcitationProblem::design_state(const Eigen::MatrixXd& free, int k) const {
  JointSample s;
  s.q = options_.anchor + free * design_q_.row(k).transpose();
  s.dq = free * design_dq_.row(k).transpose();
  s.ddq = free * design_ddq_.row(k).transpose();
  s.dddq = free * design_dddq_.row(k).transpose();
  return s;
}

Eigen::VectorXd ExcitationProblem::chain(const StateRow& ds, int k) const {
  const Eigen::Index m = design_q_.cols();
  Eigen::VectorXd out(kNumJoints * m);
  for (int j = 0; j < kNumJoints; ++j)
    out.segment(j * m, m) = ds[j] * design_q_.row(k).transpose() + ds[kNumJoints + j] * design_dq_.row(k).transpose() +
                            ds[2 * kNumJoints + j] * design_ddq_.row(k).transpose();
  return out;
}

namespace {

Eigen::MatrixXd free_matrix(const std::vector<double>& x, Eigen::Index m) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(x.data(), kNumJoints, m);
}

}  // namespace

double ExcitationProblem::criterion(const std::vector<double>& x, std::vector<double>* gradient) const {
  const Eigen::MatrixXd free = free_matrix(x, design_q_.cols());
  const int samples = static_cast<int>(design_q_.rows());
  const double periods = options_.periods;
  std::vector<JointSample> states;
  for (int k = 0; k < samples; ++k) states.push_back(design_state(free, k));
  const Eigen::MatrixXd W = id_.stacked_scaled(states);   // all states at once (dynamics/batch.hpp)
  const double lambda = options_.task.empty() ? 0.0 : options_.task_weight;
  Eigen::MatrixXd A = periods * W.transpose() * W;
  if (options_.prior_information.size() > 0) A += options_.prior_information;
  const Criterion c = design_value(A, lambda);
  if (gradient) {
    // dPhi/dW = 2 P W dPhi/dA = G. Per sample, dPhi/ds = d/ds <G_k, W_k(s)> with W_k = Sigma^-1/2 R S, i.e.
    // <H, R(s)> with H = Sigma^-1/2 G_k S. The inertial part is phi(s) = sum_j Y_j(s) h_j (row j of the
    // regressor, h_j row j of H on the base columns); its derivatives in (q, dq, ddq) by forward
    // differences, the sample and its 21 perturbed states in one batch of regressors; the friction
    // columns analytically.
    const Eigen::MatrixXd G = 2.0 * periods * W * c.gradient;
    const int nb = id_.base_parameters();
    Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(x.size()));
    std::vector<JointSample> around(1 + kState);   // the sample, then each perturbed state
    Eigen::MatrixXd Y;
    for (int k = 0; k < samples; ++k) {
      const JointSample& s = states[static_cast<std::size_t>(k)];
      const Eigen::MatrixXd H = id_.noise_sigma().cwiseInverse().asDiagonal() * G.middleRows(kNumJoints * k, kNumJoints) *
                                id_.column_scale().asDiagonal();
      Eigen::Matrix<double, kNumJoints, kInertialParameters> h = Eigen::Matrix<double, kNumJoints, kInertialParameters>::Zero();
      h(Eigen::all, id_.base_columns()) = H.leftCols(nb);
      around[0] = s;
      for (int i = 0; i < kState; ++i) around[static_cast<std::size_t>(1 + i)] = perturbed(s, i, kStep);
      inertial_regressor_batch(model_, state_batch(around), Y);
      const auto phi = [&](int m) { return Y.middleRows<kNumJoints>(kNumJoints * m).cwiseProduct(h).sum(); };
      const double phi0 = phi(0);
      StateRow ds;
      for (int i = 0; i < kState; ++i) ds[i] = (phi(1 + i) - phi0) / kStep;
      for (int j = 0; j < kNumJoints; ++j) {   // d/d dq_j of dq_j and tanh(dq_j / v)
        const int col = nb + kFrictionParametersPerJoint * j;
        const double th = std::tanh(s.dq[j] / kCoulombVelocity);
        ds[kNumJoints + j] += H(j, col) + H(j, col + 1) * (1.0 - th * th) / kCoulombVelocity;
      }
      g += chain(ds, k);
    }
    gradient->assign(g.data(), g.data() + g.size());
  }
  return c.value;
}

std::vector<std::string> ExcitationProblem::margin_names() const {
  std::vector<std::string> names;
  for (int group = 0; group < kGroups; ++group)
    for (int j = 0; j < kNumJoints; ++j) names.push_back(std::string(kGroupNames[group]) + " joint " + std::to_string(j + 1));
  names.insert(names.end(), {"power", "tool speed"});
  if (options_.clearance) names.push_back("clearance");
  return names;
}

std::vector<double> ExcitationProblem::margins(const std::vector<double>& x, std::vector<double>* jacobian) const {
  const Eigen::Index m = design_q_.cols(), n = kNumJoints * m;
  const Eigen::MatrixXd free = free_matrix(x, m);
  const JointLimits& lim = model_.parameters().joint_limits;
  const ExcitationLimits& f = options_.limits;
  const bool grad = jacobian != nullptr;
  const Vector7 hi = lim.q_max.array() - f.position_margin, lo = lim.q_min.array() + f.position_margin;
  const Vector7 half = 0.5 * (hi - lo);
  std::vector<SmoothMin> groups(kGroups * kNumJoints + 2 + (options_.clearance ? 1 : 0));
  SmoothMin& power = groups[kGroups * kNumJoints];
  SmoothMin& tool = groups[kGroups * kNumJoints + 1];
  const auto block = [&](int j, const Eigen::MatrixXd& design, int k, double scale) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
    if (grad) g.segment(j * m, m) = scale * design.row(k).transpose();
    return g;
  };
  const Eigen::VectorXd none;
  Data data;
  Matrix6x7 J, J_h;
  for (int k = 0; k < design_q_.rows(); ++k) {
    const JointSample s = design_state(free, k);
    // Torque (RNEA with the tool + the model's friction) and its state derivatives. Friction acts per
    // joint; a linear law jumps at dq = 0 (sign), so its slope is taken from two points on the side of
    // the motion (viscous part only there; the sigmoid of Gaz et al. is smooth anyway).
    const FrictionModel& friction = model_.parameters().friction;
    const auto rigid = [&](const JointSample& state) {
      Vector7 tau;
      rnea(model_, data, state.q, state.dq, state.ddq, tau);
      return tau;
    };
    const Vector7 tau_rigid = rigid(s);
    const Vector7 tau = tau_rigid + friction_torque(friction, s.dq);
    Eigen::Matrix<double, kNumJoints, kState> dtau;
    if (grad) {
      for (int i = 0; i < kState; ++i) dtau.col(i) = (rigid(perturbed(s, i, kStep)) - tau_rigid) / kStep;
      const Vector7 side = s.dq.unaryExpr([](double v) { return v < 0.0 ? -kStep : kStep; });
      const Vector7 slope = (friction_torque(friction, s.dq + 2.0 * side) - friction_torque(friction, s.dq + side)).cwiseQuotient(side);
      dtau.middleCols<kNumJoints>(kNumJoints).diagonal() += slope;
    }
    // FR3: the velocity bounds move with q.
    const Vector7 up = f.dq * lim.dq_upper(s.q), down = f.dq * lim.dq_lower(s.q);
    Vector7 dup = Vector7::Zero(), ddown = Vector7::Zero();
    if (grad && lim.position_based_velocity) {
      dup = (f.dq * lim.dq_upper(s.q + Vector7::Constant(kStep)) - up) / kStep;   // elementwise in q
      ddown = (f.dq * lim.dq_lower(s.q + Vector7::Constant(kStep)) - down) / kStep;
    }
    for (int j = 0; j < kNumJoints; ++j) {
      SmoothMin& q = groups[kPosition * kNumJoints + j];
      q.add((hi[j] - s.q[j]) / half[j], block(j, design_q_, k, -1.0 / half[j]));
      q.add((s.q[j] - lo[j]) / half[j], block(j, design_q_, k, 1.0 / half[j]));
      SmoothMin& v = groups[kVelocity * kNumJoints + j];
      const double vs = f.dq * lim.dq_max[j];
      Eigen::VectorXd gu = block(j, design_dq_, k, -1.0 / vs), gd = block(j, design_dq_, k, 1.0 / vs);
      if (grad) {
        gu += block(j, design_q_, k, dup[j] / vs);
        gd -= block(j, design_q_, k, ddown[j] / vs);
      }
      v.add((up[j] - s.dq[j]) / vs, gu);
      v.add((s.dq[j] - down[j]) / vs, gd);
      const double as = f.ddq * lim.ddq_max[j], js = f.dddq * lim.dddq_max[j], ts = f.tau * lim.tau_max[j];
      groups[kAcceleration * kNumJoints + j].add(1.0 - s.ddq[j] / as, block(j, design_ddq_, k, -1.0 / as));
      groups[kAcceleration * kNumJoints + j].add(1.0 + s.ddq[j] / as, block(j, design_ddq_, k, 1.0 / as));
      groups[kJerk * kNumJoints + j].add(1.0 - s.dddq[j] / js, block(j, design_dddq_, k, -1.0 / js));
      groups[kJerk * kNumJoints + j].add(1.0 + s.dddq[j] / js, block(j, design_dddq_, k, 1.0 / js));
      const Eigen::VectorXd gt = grad ? chain(dtau.row(j) / ts, k) : none;
      groups[kTorque * kNumJoints + j].add(1.0 - tau[j] / ts, grad ? Eigen::VectorXd(-gt) : none);
      groups[kTorque * kNumJoints + j].add(1.0 + tau[j] / ts, gt);
    }
    // Power sum_j max(0, tau_j dq_j).
    double watts = 0.0;
    StateRow dwatts = StateRow::Zero();
    for (int j = 0; j < kNumJoints; ++j)
      if (tau[j] * s.dq[j] > 0.0) {
        watts += tau[j] * s.dq[j];
        if (grad) {
          dwatts += s.dq[j] * dtau.row(j);
          dwatts[kNumJoints + j] += tau[j];
        }
      }
    power.add(1.0 - watts / f.power, grad ? Eigen::VectorXd(-chain(dwatts, k) / f.power) : none);
    // Tool (TCP) speed |J_v(q) dq|; dJ/dq by forward differences.
    forward_kinematics(model_, data, s.q);
    zero_jacobian(data, Frame::kEndEffector, J);
    const Vector3 v = J.topRows<3>() * s.dq;
    const double speed = v.norm();
    Eigen::VectorXd gv = none;
    if (grad) {
      StateRow dspeed = StateRow::Zero();
      if (speed > 0.0) {
        for (int i = 0; i < kNumJoints; ++i) {
          forward_kinematics(model_, data, s.q + kStep * Vector7::Unit(i));
          zero_jacobian(data, Frame::kEndEffector, J_h);
          dspeed[i] = v.dot((J_h.topRows<3>() - J.topRows<3>()) * s.dq) / (kStep * speed);
        }
        dspeed.segment<kNumJoints>(kNumJoints) = (J.topRows<3>().transpose() * v / speed).transpose();
      }
      gv = -chain(dspeed, k) / f.tool_speed;
    }
    tool.add(1.0 - speed / f.tool_speed, gv);
    if (options_.clearance) {
      const double c = options_.clearance(s.q);
      Eigen::VectorXd gc = none;
      if (grad) {
        StateRow dc = StateRow::Zero();
        for (int i = 0; i < kNumJoints; ++i) dc[i] = (options_.clearance(s.q + kStep * Vector7::Unit(i)) - c) / kStep;
        gc = chain(dc, k) / kClearanceScale;
      }
      groups.back().add((c - options_.clearance_buffer) / kClearanceScale, gc);
    }
  }
  std::vector<double> out;
  if (grad) jacobian->assign(groups.size() * n, 0.0);
  Eigen::VectorXd g;
  for (std::size_t c = 0; c < groups.size(); ++c) {
    out.push_back(groups[c].evaluate(options_.sharpness, grad ? &g : nullptr));
    if (grad) std::copy(g.data(), g.data() + n, jacobian->begin() + static_cast<std::ptrdiff_t>(c * n));
  }
  return out;
}

std::vector<double> ExcitationProblem::random_start(unsigned index) const {
  std::mt19937_64 engine(options_.seed * 1000003ull + index);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> direction(static_cast<std::size_t>(variables()));
  for (double& v : direction) v = uniform(engine);
  const auto scaled = [&](double s) {
    std::vector<double> x = direction;
    for (double& v : x) v *= s;
    return x;
  };
  const auto feasible = [&](double s) {
    const auto m = margins(scaled(s), nullptr);
    return *std::min_element(m.begin(), m.end()) >= 0.0;
  };
  double good = 0.0, bad = 1.0;
  while (feasible(bad) && bad < 64.0) good = bad, bad *= 2.0;
  for (int i = 0; i < 30 && bad - good > 1e-3 * bad; ++i) {
    const double mid = 0.5 * (good + bad);
    (feasible(mid) ? good : bad) = mid;
  }
  return scaled(good);
}

Eigen::MatrixXd ExcitationProblem::information(const FourierSeries& series, double duration) const {
  std::vector<JointSample> samples;
  const auto count = static_cast<long>(std::ceil(duration * options_.design_rate_hz - 1e-9));
  for (long k = 0; k < count; ++k) samples.push_back(series.sample(static_cast<double>(k) / options_.design_rate_hz));
  const Eigen::MatrixXd W = id_.stacked_scaled(samples);
  return W.transpose() * W;
}

ExcitationCriteria ExcitationProblem::evaluate(const FourierSeries& series, double duration) const {
  Eigen::MatrixXd A = information(series, duration);
  if (options_.prior_information.size() > 0) A += options_.prior_information;
  Eigen::MatrixXd task;
  if (!options_.task.empty()) task = id_.stacked_scaled(options_.task);
  ExcitationCriteria out;
  out.identifiability = identifiability_of_information(id_, A, task);
  const double lambda = options_.task.empty() ? 0.0 : options_.task_weight;
  out.criterion = design_value(A, lambda).value;
  return out;
}

LimitUsage ExcitationProblem::usage(const FourierSeries& series, double duration, double rate_hz) const {
  const JointLimits& lim = model_.parameters().joint_limits;
  const ExcitationLimits& f = options_.limits;
  const Vector7 hi = lim.q_max.array() - f.position_margin, lo = lim.q_min.array() + f.position_margin;
  const Vector7 middle = 0.5 * (hi + lo), half = 0.5 * (hi - lo);
  LimitUsage u;
  Data data;
  Matrix6x7 J;
  Vector7 previous_tau;
  const auto count = static_cast<long>(std::floor(duration * rate_hz + 1e-9));
  for (long k = 0; k <= count; ++k) {
    const JointSample s = series.sample(static_cast<double>(k) / rate_hz);
    Vector7 tau;
    rnea(model_, data, s.q, s.dq, s.ddq, tau);
    tau += friction_torque(model_.parameters().friction, s.dq);
    const Vector7 up = f.dq * lim.dq_upper(s.q), down = f.dq * lim.dq_lower(s.q);
    for (int j = 0; j < kNumJoints; ++j) {
      const double dq_use = s.dq[j] >= 0.0 ? (s.dq[j] == 0.0 ? 0.0 : s.dq[j] / up[j]) : s.dq[j] / down[j];
      u.dq[j] = std::max(u.dq[j], dq_use);
    }
    u.q = u.q.cwiseMax((s.q - middle).cwiseAbs().cwiseQuotient(half));
    u.ddq = u.ddq.cwiseMax(s.ddq.cwiseAbs().cwiseQuotient(f.ddq * lim.ddq_max));
    u.dddq = u.dddq.cwiseMax(s.dddq.cwiseAbs().cwiseQuotient(f.dddq * lim.dddq_max));
    u.tau = u.tau.cwiseMax(tau.cwiseAbs().cwiseQuotient(f.tau * lim.tau_max));
    if (k > 0) u.dtau = u.dtau.cwiseMax(((tau - previous_tau) * rate_hz).cwiseAbs() / f.dtau);   // as the robot differences
    previous_tau = tau;
    u.power = std::max(u.power, tau.cwiseProduct(s.dq).cwiseMax(0.0).sum() / f.power);
    forward_kinematics(model_, data, s.q);
    zero_jacobian(data, Frame::kEndEffector, J);
    u.tool_speed = std::max(u.tool_speed, (J.topRows<3>() * s.dq).norm() / f.tool_speed);
    if (options_.clearance) u.min_clearance = std::min(u.min_clearance, options_.clearance(s.q));
  }
  return u;
}

FourierSeries time_scaled(const FourierSeries& series, double k) {
  if (!(k > 0.0) || !std::isfinite(k)) throw std::invalid_argument("time scaling: k must be positive and finite");
  return FourierSeries(series.fundamental_hz() / k, series.a() / k, series.b() / k, series.q0());
}

double time_scale_into_limits(const ExcitationProblem& problem, const FourierSeries& series, double rate_hz) {
  const Model& model = problem.identification().model();
  const JointLimits& lim = model.parameters().joint_limits;
  const ExcitationLimits& f = problem.options().limits;
  const LimitUsage u = problem.usage(series, series.period(), rate_hz);
  if (u.q.maxCoeff() > 1.0) throw std::runtime_error("time scaling: positions are outside the limits (" + u.worst() + ")");
  if (u.min_clearance < 0.0) throw std::runtime_error("time scaling: the path is in collision; time does not change that");
  // Hollerbach: tau_k - g = (tau_1 - g)/k^2 (no friction), so |tau_k| <= |g| + |tau_f| + |tau_1 - g|/k^2.
  double torque = 0.0;
  Data data;
  const auto count = static_cast<long>(std::floor(series.period() * rate_hz));
  for (long k = 0; k <= count; ++k) {
    const JointSample s = series.sample(static_cast<double>(k) / rate_hz);
    Vector7 tau, g;
    rnea(model, data, s.q, s.dq, s.ddq, tau);
    gravity_torque(model, data, s.q, g);
    const Vector7 room = f.tau * lim.tau_max - g.cwiseAbs() - friction_torque(model.parameters().friction, s.dq).cwiseAbs();
    if (!((room.array() > 0.0).all()))
      throw std::runtime_error("time scaling: gravity and friction alone exceed the torque limit fraction");
    torque = std::max(torque, (tau - g).cwiseAbs().cwiseQuotient(room).maxCoeff());
  }
  double k = std::max({u.dq.maxCoeff(), std::sqrt(u.ddq.maxCoeff()), std::cbrt(u.dddq.maxCoeff()), std::sqrt(torque),
                       u.dtau.maxCoeff(), u.power, u.tool_speed, 1e-3});
  for (int i = 0; i < 1000; ++i, k *= 1.01)
    if (problem.usage(time_scaled(series, k), series.period() * k, rate_hz).within()) return k;
  throw std::runtime_error("time scaling: no k <= 1000 brings the trajectory within the limits");
}

ExcitationResult ExcitationProblem::solve() const {
  // Multistart: the best of the random starts (each shrunk into the design margins).
  std::vector<double> best;
  double best_value = INFINITY;
  for (int r = 0; r < options_.random_starts; ++r) {
    std::vector<double> x = random_start(static_cast<unsigned>(r));
    const double value = criterion(x, nullptr);
    if (value < best_value) best_value = value, best = std::move(x);
  }
  ExcitationResult result{series(best), 1.0, 1.0, 0.0, {}, {}, best_value, 0, ""};

  // MMA (Svanberg 2002, NLopt's conservative CCSA variant): each outer iterate is feasible when the
  // start is, so any evaluation budget ends on a plan within the design margins. SLSQP was tried
  // first: its quasi-Newton steps left the feasible set far (margins -3) and spent the budget coming
  // back. The best point whose design margins all hold is kept.
  nlopt::opt opt(nlopt::LD_MMA, static_cast<unsigned>(variables()));
  struct Context {
    const ExcitationProblem* problem;
    std::vector<double> last_x;
    double last_value = INFINITY;
    std::vector<double> best_x;
    double best_value;
    int evaluations = 0;
  } context{this, {}, INFINITY, best, best_value, 0};
  opt.set_min_objective(
      [](const std::vector<double>& x, std::vector<double>& grad, void* data) {
        auto* c = static_cast<Context*>(data);
        ++c->evaluations;
        report(c->problem->options_.progress, "optimising", c->evaluations, c->problem->options_.max_evaluations);
        c->last_x = x;
        c->last_value = c->problem->criterion(x, grad.empty() ? nullptr : &grad);
        return c->last_value;
      },
      &context);
  const unsigned constraints = static_cast<unsigned>(margin_names().size());
  opt.add_inequality_mconstraint(
      [](unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
        auto* c = static_cast<Context*>(data);
        const std::vector<double> point(x, x + n);
        std::vector<double> jacobian;
        const std::vector<double> margins = c->problem->margins(point, grad ? &jacobian : nullptr);
        for (unsigned i = 0; i < m; ++i) result[i] = -margins[i];   // NLopt: c(x) <= 0
        if (grad)
          for (std::size_t i = 0; i < jacobian.size(); ++i) grad[i] = -jacobian[i];
        if (point == c->last_x && c->last_value < c->best_value &&
            *std::min_element(margins.begin(), margins.end()) >= 0.0)
          c->best_x = point, c->best_value = c->last_value;
      },
      &context, std::vector<double>(constraints, 1e-6));
  opt.set_lower_bounds(-3.0);
  opt.set_upper_bounds(3.0);
  opt.set_maxeval(options_.max_evaluations);
  opt.set_xtol_rel(1e-5);
  opt.set_ftol_abs(1e-7);
  std::vector<double> x = best;
  double value = best_value;
  try {
    result.optimizer_result = nlopt_result_to_string(static_cast<nlopt_result>(opt.optimize(x, value)));
  } catch (const nlopt::roundoff_limited&) {
    result.optimizer_result = "ROUNDOFF_LIMITED";
  } catch (const std::runtime_error& e) {
    result.optimizer_result = std::string("stopped: ") + e.what();
  }
  result.evaluations = context.evaluations;

  // Check at 1 kHz. A contact between design samples: shrink toward the anchor (clearance > 0 there)
  // by bisection. A rate limit over: slow down in closed form.
  const auto shrunk = [&](double s) {
    std::vector<double> x = context.best_x;
    for (double& v : x) v *= s;
    return this->series(x);
  };
  FourierSeries series = this->series(context.best_x);
  result.usage = usage(series, series.period());
  if (result.usage.min_clearance < 0.0) {
    double good = 0.0, bad = 1.0;
    for (int i = 0; i < 12; ++i) {
      const double mid = 0.5 * (good + bad);
      const FourierSeries candidate = shrunk(mid);
      (usage(candidate, candidate.period()).min_clearance >= 0.0 ? good : bad) = mid;
    }
    result.amplitude_scale = good;
    series = shrunk(good);
    result.usage = usage(series, series.period());
  }
  if (!result.usage.within()) {
    result.time_scale = std::max(1.0, time_scale_into_limits(*this, series));
    series = time_scaled(series, result.time_scale);
    result.usage = usage(series, series.period());
  }
  result.series = series;
  result.duration = options_.periods * series.period();
  result.criteria = evaluate(series, result.duration);
  return result;
}

MultiAnchorExcitation solve_anchors(const Model& model, const ExcitationOptions& options, const std::vector<Vector7>& anchors) {
  if (anchors.empty()) throw std::invalid_argument("excitation: no anchors");
  MultiAnchorExcitation out;
  ExcitationOptions o = options;
  for (std::size_t a = 0; a < anchors.size(); ++a) {
    o.anchor = anchors[a];
    o.seed = options.seed + static_cast<unsigned>(a);
    const std::string anchor_stage = "anchor " + std::to_string(a + 1) + " of " + std::to_string(anchors.size()) + ": ";
    if (options.progress)
      o.progress = [&](std::string_view stage, double done, double total) {
        options.progress(anchor_stage + std::string(stage), done, total);
      };
    const ExcitationProblem problem(model, o);
    out.segments.push_back(problem.solve());
    const ExcitationResult& r = out.segments.back();
    const Eigen::MatrixXd segment = problem.information(r.series, r.duration);
    o.prior_information = o.prior_information.size() > 0 ? Eigen::MatrixXd(o.prior_information + segment) : segment;
    out.criteria = r.criteria;   // with the prior: every segment so far
  }
  return out;
}

}  // namespace csp::planners
