#include "csp/gap/effects.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <optional>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/friction.hpp"
#include "csp/dynamics/model.hpp"

namespace csp::gap {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

Eigen::Index rows_of(int sample) { return kNumJoints * static_cast<Eigen::Index>(sample); }

std::vector<double> values(const VectorXd& v, Eigen::Index begin, Eigen::Index count, Eigen::Index stride = 1) {
  std::vector<double> out;
  for (Eigen::Index i = 0; i < count; ++i) out.push_back(v[begin + i * stride]);
  return out;
}

// A linear effect with one parameter per joint: joint j's torque is theta_j x_j(sample k).
// `parameter` names theta in the JSON, in units of `scale` theta.
class PerJointLinearEffect : public LinearEffect {
 public:
  PerJointLinearEffect(std::string name, std::string parameter, double scale)
      : name_(std::move(name)), parameter_(std::move(parameter)), scale_(scale) {}
  std::string name() const override { return name_; }
  int size() const override { return kNumJoints; }
  MatrixXd regressor(const Part& part) const override {
    MatrixXd Y = MatrixXd::Zero(part.rows(), kNumJoints);
    for (std::size_t k = 0; k < part.samples.size(); ++k)
      for (int j = 0; j < kNumJoints; ++j) Y(rows_of(static_cast<int>(k)) + j, j) = x(part, k, j);
    return Y;
  }
  nlohmann::json describe(const VectorXd& theta) const override {
    return {{parameter_, values(scale_ * theta, 0, kNumJoints)}};
  }

 protected:
  virtual double x(const Part& part, std::size_t k, int j) const = 0;

 private:
  std::string name_, parameter_;
  double scale_;
};

// --- sensor_offset: a constant bias per joint torque sensor -------------------------------------
class SensorOffset : public PerJointLinearEffect {
 public:
  SensorOffset() : PerJointLinearEffect("sensor_offset", "offset_Nm", 1.0) {}

 protected:
  double x(const Part&, std::size_t, int) const override { return 1.0; }
};

// --- armature: rotor inertia reflected to the link side, I_a,j ddq_j -----------------------------
class Armature : public PerJointLinearEffect {
 public:
  Armature() : PerJointLinearEffect("armature", "inertia_kgm2", 1.0) {}

 protected:
  double x(const Part& part, std::size_t k, int j) const override { return part.samples.ddq[k][j]; }
};

// --- base_tilt: gravity direction off by small rotations about base x and y ----------------------
class BaseTilt : public LinearEffect {
 public:
  std::string name() const override { return "base_tilt"; }
  int size() const override { return 2; }
  MatrixXd regressor(const Part& part) const override { return part.tilt; }
  nlohmann::json describe(const VectorXd& theta) const override {
    const double degrees = 180.0 / M_PI;
    return {{"about_x_deg", degrees * theta[0]}, {"about_y_deg", degrees * theta[1]}};
  }
};

// --- time_delay: measured torque late by d: tau_m(t) = tau(t - d) ~ tau(t) - d dtau/dt ----------
class TimeDelay : public LinearEffect {
 public:
  std::string name() const override { return "time_delay"; }
  int size() const override { return 1; }
  MatrixXd regressor(const Part& part) const override { return -stack(part.samples.dtau); }
  nlohmann::json describe(const VectorXd& theta) const override {
    return {{"delay_ms", 1e3 * theta[0]}};
  }
};

// The smallest change of the 70 standard parameters that reproduces a change of the base ones (over
// the random states of `base`): one realisation of it, as base parameters fix only combinations.
VectorXd smallest_standard_change(const BaseParameters& base, const VectorXd& delta) {
  return base.random_regressor.completeOrthogonalDecomposition().solve(base.random_regressor(Eigen::all, base.columns) *
                                                                      delta);
}

// A change of the base parameters (their count, names, values), as both inertial effects report it.
nlohmann::json describe_base_change(const BaseParameters& base, const VectorXd& delta) {
  std::vector<std::string> column_names;
  static const char* const kNames[] = {"m", "hx", "hy", "hz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};
  for (int c : base.columns)
    column_names.push_back(std::string(kNames[c % kLinkParameters]) + "_" + std::to_string(c / kLinkParameters + 1));
  return {{"base_parameter_count", base.columns.size()},
          {"base_parameter_columns", column_names},
          {"delta", values(delta, 0, delta.size())}};
}

// --- inertial_parameters: errors of the identifiable base parameters ----------------------------
class InertialParameters : public LinearEffect {
 public:
  explicit InertialParameters(const Model& model) : model_(model), base_(base_parameters(model)) {}
  std::string name() const override { return "inertial_parameters"; }
  int size() const override { return static_cast<int>(base_.columns.size()); }
  MatrixXd regressor(const Part& part) const override { return part.inertial(Eigen::all, base_.columns); }

  nlohmann::json describe(const VectorXd& theta) const override { return describe_base_change(base_, theta); }

  // Physical consistency of the corrected model. Base parameters fix only combinations of the 70
  // standard ones, so we check one realisation: the smallest change of the standard parameters
  // reproducing the fitted base-parameter change. Checked: every link's mass > 0 and its inertia
  // about the CoM positive definite with the triangle inequality; and the mass matrix positive
  // definite at the random states used for the base parameters (the identified dynamics are
  // physically meaningful even when the realisation is not).
  nlohmann::json consistency(const VectorXd& theta) const override {
    const VectorXd standard = smallest_standard_change(base_, theta);
    bool links_physical = true;
    double largest_mass_change = 0.0;
    for (int i = 0; i < kNumJoints; ++i) {
      const LinkParameters change = standard.segment<kLinkParameters>(kLinkParameters * i);
      const SpatialInertia body = spatial_inertia(link_parameters(model_.body(i)) + change);
      largest_mass_change = std::max(largest_mass_change, std::abs(change[0]));
      links_physical = links_physical && body.mass > 0.0 && is_physical_inertia(rigid_body(body).inertia);
    }
    bool mass_matrix_pd = links_physical;
    if (!links_physical) {  // the realisation is not a set of bodies; check M = Y(q, 0, e_j) directly
      mass_matrix_pd = true;
      const InertialRegressor regressor(model_);
      Data data;
      for (const Vector7& q : base_.random_q) {
        crba(model_, data, q);
        Matrix7 M = data.mass_matrix;
        const Vector7 gravity_change = regressor(data, q, Vector7::Zero(), Vector7::Zero()) * standard;
        for (int j = 0; j < kNumJoints; ++j)
          M.col(j) += regressor(data, q, Vector7::Zero(), Vector7::Unit(j)) * standard - gravity_change;
        mass_matrix_pd = mass_matrix_pd && Eigen::LLT<Matrix7>(M).info() == Eigen::Success;
      }
    }
    return {{"largest_link_mass_change_kg", largest_mass_change},
            {"realisation_physically_consistent", links_physical},
            {"mass_matrix_positive_definite", mass_matrix_pd}};
  }

 private:
  Model model_;
  BaseParameters base_;
};

// --- inertial_parameters over physical links (docs/gap.md, "Physically consistent fits") -----------
// The same torque, Y (pi - pi_model), with the 70 standard parameters pi of the links (the load
// lumped into link 7, as the regressor has it) written in the log-Cholesky parametrisation
// (dynamics/regressor.hpp): every parameter vector is a set of physical links, so the fit is
// unconstrained yet physical. Nonlinear (70 parameters, 43 identifiable): the diagnosis uses it to
// refit a verdict whose linear inertial fit no physical links realise, not in the selection.
class PhysicalInertialParameters : public Effect {
 public:
  explicit PhysicalInertialParameters(const Model& model) : base_(base_parameters(model)) {
    for (int i = 0; i < kNumJoints; ++i) nominal_.segment<kLinkParameters>(kLinkParameters * i) = link_parameters(model.body(i));
    // The base-parameter change of a standard one: Y_base C = Y over the random states.
    combination_ = base_.random_regressor(Eigen::all, base_.columns).colPivHouseholderQr().solve(base_.random_regressor);
  }
  std::string name() const override { return "inertial_parameters"; }
  int size() const override { return kInertialParameters; }
  VectorXd torque(const Part& part, const VectorXd& theta) const override { return part.inertial * change(theta); }
  MatrixXd jacobian(const Part& part, const VectorXd& theta) const override {
    MatrixXd J(part.rows(), size());
    for (int i = 0; i < kNumJoints; ++i)
      J.middleCols<kLinkParameters>(kLinkParameters * i).noalias() =
          part.inertial.middleCols<kLinkParameters>(kLinkParameters * i) *
          from_log_cholesky_jacobian(theta.segment<kLinkParameters>(kLinkParameters * i));
    return J;
  }
  // Toward the linear fit of the base parameters to `target`, realised by the smallest change of the
  // standard ones, as far as every link stays a physical body (bisection on the fraction of the way):
  // the model's links are close to the boundary (thin links: flat mass distributions), so the whole
  // way is rarely physical.
  VectorXd initial_guess(const Part& part, const VectorXd& target) const override {
    const VectorXd delta = part.inertial(Eigen::all, base_.columns).colPivHouseholderQr().solve(target);
    const VectorXd change = smallest_standard_change(base_, delta);
    auto physical = [&](double fraction) {
      for (int i = 0; i < kNumJoints; ++i) {
        const auto link = Eigen::seqN(kLinkParameters * i, kLinkParameters);
        if (!physically_consistent(nominal_(link) + fraction * change(link))) return false;
      }
      return true;
    };
    double low = 0.0, high = 1.0;
    if (physical(high)) low = high;
    while (high - low > 1e-3) {
      const double middle = 0.5 * (low + high);
      if (physical(middle))
        low = middle;
      else
        high = middle;
    }
    VectorXd theta(size());
    for (int i = 0; i < kNumJoints; ++i) {
      const auto link = Eigen::seqN(kLinkParameters * i, kLinkParameters);
      theta(link) = to_log_cholesky(nominal_(link) + low * change(link));
    }
    return theta;
  }
  nlohmann::json describe(const VectorXd& theta) const override {
    return describe_base_change(base_, combination_ * change(theta));
  }
  nlohmann::json consistency(const VectorXd& theta) const override {
    std::vector<double> mass;
    std::vector<std::vector<double>> com;
    double largest_mass_change = 0.0;
    for (int i = 0; i < kNumJoints; ++i) {
      const RigidBodyInertia body = rigid_body(spatial_inertia(from_log_cholesky(theta.segment<kLinkParameters>(kLinkParameters * i))));
      mass.push_back(body.mass), com.push_back({body.com.x(), body.com.y(), body.com.z()});
      largest_mass_change = std::max(largest_mass_change, std::abs(body.mass - nominal_[kLinkParameters * i]));
    }
    return {{"fitted_over_physical_links", true},
            {"link_mass_kg", mass},
            {"link_com_m", com},
            {"largest_link_mass_change_kg", largest_mass_change},
            {"realisation_physically_consistent", true},
            {"mass_matrix_positive_definite", true}};
  }

 private:
  VectorXd change(const VectorXd& theta) const {
    VectorXd pi(kInertialParameters);
    for (int i = 0; i < kNumJoints; ++i)
      pi.segment<kLinkParameters>(kLinkParameters * i) = from_log_cholesky(theta.segment<kLinkParameters>(kLinkParameters * i));
    return pi - nominal_;
  }
  BaseParameters base_;
  Eigen::Matrix<double, kInertialParameters, 1> nominal_;
  MatrixXd combination_;
};

// --- payload: a point mass on the flange (mass m, CoM c in the flange frame) --------------------
// Parameters (m, h = m c): the torque is linear in (m, h) except for the point mass's rotational
// inertia about the flange, (|h|^2 1 - h h^T) / m, which is small; the fit starts from the linear
// part and Gauss-Newton does the rest.
class Payload : public Effect {
 public:
  explicit Payload(const Model& model) : link7_T_flange_(model.parameters().link7_T_flange) {}
  std::string name() const override { return "payload"; }
  int size() const override { return 4; }

  VectorXd torque(const Part& part, const VectorXd& theta) const override {
    return part.inertial.rightCols<kLinkParameters>() * link7_parameters(theta, true);
  }
  VectorXd initial_guess(const Part& part, const VectorXd& target) const override {
    MatrixXd columns(part.rows(), 4);
    for (int k = 0; k < 4; ++k)
      columns.col(k) = part.inertial.rightCols<kLinkParameters>() * link7_parameters(VectorXd::Unit(4, k), false);
    return columns.colPivHouseholderQr().solve(target);
  }
  nlohmann::json describe(const VectorXd& theta) const override {
    const double m = theta[0];
    return {{"mass_kg", m}, {"com_m", values(theta / m, 1, 3)}};
  }

 private:
  // The payload's standard parameters in the link-7 frame.
  LinkParameters link7_parameters(const VectorXd& theta, bool second_moment) const {
    const double m = theta[0];
    const Vector3 h = theta.segment<3>(1);
    const bool defined = second_moment && std::abs(m) > 1e-6;
    const Matrix3 I =
        defined ? ((h.squaredNorm() * Matrix3::Identity() - h * h.transpose()) / m).eval() : Matrix3::Zero();
    return link_parameters(SpatialInertia{m, h, I}.expressed_in(link7_T_flange_));
  }
  Transform link7_T_flange_;
};

// --- joint_friction: per joint, phi1 (s(phi2 (dq + phi3)) - s(phi2 phi3)) + f_v dq ---------------
// The Gaz et al. (2019) sigmoid (gaz_friction; s the logistic function) plus viscous friction; a
// steep sigmoid with phi3 = 0 is Coulomb friction of phi1 / 2. Parameters per joint:
// (phi1, ln phi2, phi3, v); ln phi2 keeps phi2 positive. v is f_v itself, or, with a viscous floor
// (the physical refit: the model's own viscous friction plus f_v never below zero), the ln of f_v's
// distance above the floor.
class JointFriction : public Effect {
 public:
  JointFriction() = default;
  explicit JointFriction(const Vector7& viscous_floor) : viscous_floor_(viscous_floor) {}
  std::string name() const override { return "joint_friction"; }
  int size() const override { return 4 * kNumJoints; }

  // friction_law, with each joint's sigmoid built once for all its samples.
  VectorXd torque(const Part& part, const VectorXd& theta) const override {
    VectorXd tau(part.rows());
    for (int j = 0; j < kNumJoints; ++j) {
      const GazFriction sigmoid = law(theta, j);
      const double viscous = viscous_of(theta, j);
      for (std::size_t k = 0; k < part.samples.size(); ++k) {
        const double dq = part.samples.dq[k][j];
        tau[rows_of(static_cast<int>(k)) + j] = sigmoid(dq) + viscous * dq;
      }
    }
    return tau;
  }

  MatrixXd jacobian(const Part& part, const VectorXd& theta) const override {
    MatrixXd J = MatrixXd::Zero(part.rows(), size());
    for (int j = 0; j < kNumJoints; ++j) {
      const GazFriction sigmoid = law(theta, j);
      const double phi2 = std::exp(theta[4 * j + 1]);
      const double viscous_slope = viscous_floor_ ? viscous_of(theta, j) - (*viscous_floor_)[j] : 1.0;  // d f_v / d v
      for (std::size_t k = 0; k < part.samples.size(); ++k) {
        const Eigen::Index r = rows_of(static_cast<int>(k)) + j;
        const double dq = part.samples.dq[k][j];
        const GazFrictionGradient gradient = sigmoid.gradient(dq);
        J(r, 4 * j) = gradient.phi1;
        J(r, 4 * j + 1) = phi2 * gradient.phi2;   // d/d(ln phi2) = phi2 d/dphi2
        J(r, 4 * j + 2) = gradient.phi3;
        J(r, 4 * j + 3) = viscous_slope * dq;
      }
    }
    return J;
  }

  // Per joint, a grid over (phi2, phi3) with (phi1, f_v) by least squares at each point.
  VectorXd initial_guess(const Part& part, const VectorXd& target) const override {
    VectorXd theta(size());
    const Eigen::Index n = part.rows() / kNumJoints;
    for (int j = 0; j < kNumJoints; ++j) {
      double best = std::numeric_limits<double>::infinity();
      for (double log_phi2 = std::log(2.0); log_phi2 < std::log(120.0); log_phi2 += std::log(120.0 / 2.0) / 10.0)
        for (double phi3 = -0.1; phi3 < 0.1001; phi3 += 0.025) {
          Eigen::MatrixX2d A(n, 2);
          VectorXd b(n);
          const GazFriction unit_sigmoid(1.0, std::exp(log_phi2), phi3);
          for (Eigen::Index k = 0; k < n; ++k) {
            const double dq = part.samples.dq[k][j];
            A(k, 0) = unit_sigmoid(dq);
            A(k, 1) = dq;
            b[k] = target[kNumJoints * k + j];
          }
          const Eigen::Vector2d x = A.colPivHouseholderQr().solve(b);
          const double rss = (A * x - b).squaredNorm();
          if (rss < best) best = rss, theta.segment<4>(4 * j) << x[0], log_phi2, phi3, x[1];
        }
      // Above the floor: a least-squares viscous coefficient below it starts just above it.
      if (viscous_floor_) theta[4 * j + 3] = std::log(std::max(theta[4 * j + 3] - (*viscous_floor_)[j], 1e-4));
    }
    return theta;
  }

  nlohmann::json describe(const VectorXd& theta) const override {
    const VectorXd phi2 = theta(Eigen::seqN(1, kNumJoints, 4)).array().exp();
    VectorXd viscous(kNumJoints);
    for (int j = 0; j < kNumJoints; ++j) viscous[j] = viscous_of(theta, j);
    nlohmann::json out = {{"phi1_Nm", values(theta, 0, kNumJoints, 4)},
            {"phi2_s_per_rad", values(phi2, 0, kNumJoints)},
            {"phi3_rad_per_s", values(theta, 2, kNumJoints, 4)},
            {"viscous_Nms_per_rad", values(viscous, 0, kNumJoints)}};
    if (viscous_floor_) out["fitted_with_non_negative_viscous"] = true;
    return out;
  }

 private:
  static GazFriction law(const VectorXd& theta, int j) {
    return GazFriction(theta[4 * j], std::exp(theta[4 * j + 1]), theta[4 * j + 2]);
  }
  double viscous_of(const VectorXd& theta, int j) const {
    return viscous_floor_ ? (*viscous_floor_)[j] + std::exp(theta[4 * j + 3]) : theta[4 * j + 3];
  }
  std::optional<Vector7> viscous_floor_;
};


// --- sensor_gain: each torque sensor reads (1 + g_j) times the true torque ---------------------
// The residual is then g_j tau_j; the model's predicted torque stands in for tau_j (the gain is a
// few per cent, so the error of that stand-in is second order).
class SensorGain : public PerJointLinearEffect {
 public:
  SensorGain() : PerJointLinearEffect("sensor_gain", "gain_error_percent", 100.0) {}

 protected:
  double x(const Part& part, std::size_t k, int j) const override { return part.predicted[k][j]; }
};

// --- thermal_drift: a sensor offset that drifts linearly over the log, rate_j t -----------------
// t is the log's own time (from its first row), so a log split in two keeps one drift. A drift
// that started before the log adds a constant: that part is sensor_offset's.
class ThermalDrift : public PerJointLinearEffect {
 public:
  ThermalDrift() : PerJointLinearEffect("thermal_drift", "drift_Nm_per_min", 60.0) {}

 protected:
  double x(const Part& part, std::size_t k, int) const override { return part.samples.t[k]; }
};

// --- load_dependent_friction: coefficient_j |tau_j| sgn(dq_j), tau_j the model's torque ---------
class LoadDependentFriction : public PerJointLinearEffect {
 public:
  LoadDependentFriction() : PerJointLinearEffect("load_dependent_friction", "coefficient", 1.0) {}

 protected:
  double x(const Part& part, std::size_t k, int j) const override {
    return load_friction(1.0, part.predicted[k][j], part.samples.dq[k][j]);
  }
};

// --- position_ripple: per joint a sin(2 pi q / P) + b cos(2 pi q / P); (a, b, ln P) per joint ----
class PositionRipple : public Effect {
 public:
  std::string name() const override { return "position_ripple"; }
  int size() const override { return 3 * kNumJoints; }

  VectorXd torque(const Part& part, const VectorXd& theta) const override {
    VectorXd tau(part.rows());
    for (Eigen::Index r = 0; r < part.rows(); ++r) {
      const int j = static_cast<int>(r % kNumJoints);
      tau[r] = position_ripple(theta[3 * j], theta[3 * j + 1], std::exp(theta[3 * j + 2]),
                               part.samples.q[r / kNumJoints][j]);
    }
    return tau;
  }
  MatrixXd jacobian(const Part& part, const VectorXd& theta) const override {
    MatrixXd J = MatrixXd::Zero(part.rows(), size());
    for (Eigen::Index r = 0; r < part.rows(); ++r) {
      const int j = static_cast<int>(r % kNumJoints);
      const double a = theta[3 * j], b = theta[3 * j + 1], period = std::exp(theta[3 * j + 2]);
      const double x = 2.0 * M_PI * part.samples.q[r / kNumJoints][j] / period;
      J(r, 3 * j) = std::sin(x);
      J(r, 3 * j + 1) = std::cos(x);
      J(r, 3 * j + 2) = -x * (a * std::cos(x) - b * std::sin(x));  // dx/d(ln P) = -x
    }
    return J;
  }
  // Per joint, the best of a grid of periods (0.08..1 rad, the link-side periods that stay below
  // the smoothing filter's cut-off at the excitation's speeds) with (a, b) by least squares.
  VectorXd initial_guess(const Part& part, const VectorXd& target) const override {
    VectorXd theta(size());
    const Eigen::Index n = part.rows() / kNumJoints;
    for (int j = 0; j < kNumJoints; ++j) {
      double best = std::numeric_limits<double>::infinity();
      for (int g = 0; g <= kGrid; ++g) {
        const double period = kShortest * std::pow(kLongest / kShortest, static_cast<double>(g) / kGrid);
        Eigen::MatrixX2d A(n, 2);
        VectorXd b(n);
        for (Eigen::Index k = 0; k < n; ++k) {
          const double x = 2.0 * M_PI * part.samples.q[k][j] / period;
          A(k, 0) = std::sin(x), A(k, 1) = std::cos(x), b[k] = target[kNumJoints * k + j];
        }
        const Eigen::Vector2d ab = A.colPivHouseholderQr().solve(b);
        const double rss = (A * ab - b).squaredNorm();
        if (rss < best) best = rss, theta.segment<3>(3 * j) << ab[0], ab[1], std::log(period);
      }
    }
    return theta;
  }
  nlohmann::json describe(const VectorXd& theta) const override {
    std::vector<double> amplitude, period;
    for (int j = 0; j < kNumJoints; ++j) {
      amplitude.push_back(std::hypot(theta[3 * j], theta[3 * j + 1]));
      period.push_back(std::exp(theta[3 * j + 2]));
    }
    return {{"amplitude_Nm", amplitude}, {"period_rad", period}};
  }

 private:
  static constexpr double kShortest = 0.08, kLongest = 1.0;  // [rad]
  static constexpr int kGrid = 80;
};

// A nonlinear effect made of one shape per joint scaled by a per-joint amplitude, the shape
// depending on one shared nonlinear parameter (ln of a velocity or a distance). Parameters:
// 7 amplitudes (as the law wants them), then the shared ln parameter. The shapes change within a
// few hundredths of a rad/s or rad, faster than the smoothing filter passes: they are evaluated on
// the log's uniform grid and smoothed like the measured torque (Samples::smoothed).
class AmplitudesAndShape : public Effect {
 public:
  int size() const override { return kNumJoints + 1; }
  VectorXd torque(const Part& part, const VectorXd& theta) const override {
    return scaled(shapes(part, shared_parameter(theta[kNumJoints])), theta);
  }
  // The amplitudes' columns exactly; the shared parameter's by a forward difference.
  MatrixXd jacobian(const Part& part, const VectorXd& theta) const override {
    const double step = 1e-6 * std::max(1.0, std::abs(theta[kNumJoints]));
    MatrixXd J = MatrixXd::Zero(part.rows(), size());
    const VectorXd here = torque(part, theta);
    const std::vector<Vector7>& shape = shapes(part, shared_parameter(theta[kNumJoints]));
    for (Eigen::Index r = 0; r < part.rows(); ++r) {
      const int j = static_cast<int>(r % kNumJoints);
      J(r, j) = amplitude_derivative(theta[j]) * shape[static_cast<std::size_t>(r / kNumJoints)][j];
    }
    J.col(kNumJoints) = (scaled(shapes(part, shared_parameter(theta[kNumJoints] + step)), theta) - here) / step;
    return J;
  }
  // The best shared parameter on a grid, with the amplitudes by least squares per joint.
  VectorXd initial_guess(const Part& part, const VectorXd& target) const override {
    VectorXd theta(size());
    double best = std::numeric_limits<double>::infinity();
    for (double shared : grid()) {
      const std::vector<Vector7>& shape = shapes(part, shared);
      double rss = 0.0;
      Vector7 amplitudes;
      for (int j = 0; j < kNumJoints; ++j) {
        double sy = 0.0, ss = 0.0;
        for (std::size_t k = 0; k < shape.size(); ++k)
          sy += shape[k][j] * target[rows_of(static_cast<int>(k)) + j], ss += shape[k][j] * shape[k][j];
        amplitudes[j] = ss > 0.0 ? sy / ss : 0.0;
        rss -= ss > 0.0 ? sy * sy / ss : 0.0;
      }
      if (rss < best) {
        best = rss;
        for (int j = 0; j < kNumJoints; ++j) theta[j] = parameter_of(amplitudes[j]);
        theta[kNumJoints] = std::log(shared);
      }
    }
    return theta;
  }

 protected:
  // The shared parameter from its ln, kept on the grid's range: beyond it the shape would turn into
  // a sliding (Coulomb) law, which is joint_friction's.
  double shared_parameter(double ln_value) const {
    const std::vector<double> g = grid();
    return std::clamp(std::exp(ln_value), g.front(), g.back());
  }
  // Each sample's shape per joint for the shared parameter (a velocity or distance, > 0). A fit
  // changes the amplitudes far more often than the shared parameter, and the shapes cost most of a
  // diagnosis (a law and the smoothing filter on every grid point), so the last two are kept.
  const std::vector<Vector7>& shapes(const Part& part, double shared) const {
    for (const ShapeCache& c : cache_)
      if (c.samples == &part.samples && c.shared == shared && c.size == part.samples.size()) return c.shape;
    ShapeCache& c = cache_[next_cache_];
    next_cache_ = (next_cache_ + 1) % cache_.size();
    c = {&part.samples, shared, part.samples.size(), part.samples.smoothed(grid_shapes(part.samples, shared))};
    return c.shape;
  }
  // The shape on the uniform grid (Samples::grid_q, grid_dq).
  virtual std::vector<Vector7> grid_shapes(const Samples& samples, double shared) const = 0;
  virtual std::vector<double> grid() const = 0;
  // The amplitude from its parameter, its derivative, and the parameter from a least-squares amplitude.
  virtual double amplitude(double parameter) const { return parameter; }
  virtual double amplitude_derivative(double /*parameter*/) const { return 1.0; }
  virtual double parameter_of(double amplitude) const { return amplitude; }

 private:
  VectorXd scaled(const std::vector<Vector7>& shape, const VectorXd& theta) const {
    VectorXd tau(kNumJoints * static_cast<Eigen::Index>(shape.size()));
    for (Eigen::Index r = 0; r < tau.size(); ++r) {
      const int j = static_cast<int>(r % kNumJoints);
      tau[r] = amplitude(theta[j]) * shape[static_cast<std::size_t>(r / kNumJoints)][j];
    }
    return tau;
  }
  struct ShapeCache {
    const Samples* samples = nullptr;
    double shared = 0.0;
    std::size_t size = 0;
    std::vector<Vector7> shape;
  };
  mutable std::array<ShapeCache, 4> cache_;
  mutable std::size_t next_cache_ = 0;
};

// --- static_friction: per joint s_j sgn(dq) exp(-(dq / v_s)^2), s_j > 0 (as ln s_j), shared v_s --
class StaticFriction : public AmplitudesAndShape {
 public:
  std::string name() const override { return "static_friction"; }
  nlohmann::json describe(const VectorXd& theta) const override {
    const VectorXd excess = theta.head<kNumJoints>().array().exp();
    return {{"breakaway_excess_Nm", values(excess, 0, kNumJoints)},
            {"stribeck_velocity_rad_per_s", shared_parameter(theta[kNumJoints])}};
  }

 protected:
  std::vector<Vector7> grid_shapes(const Samples& samples, double stribeck_velocity) const override {
    std::vector<Vector7> out(samples.grid_dq.size());
    for (std::size_t k = 0; k < out.size(); ++k)
      for (int j = 0; j < kNumJoints; ++j) out[k][j] = stribeck_excess(1.0, stribeck_velocity, samples.grid_dq[k][j]);
    return out;
  }
  // Stribeck velocities of geared robot joints are a few hundredths of a rad/s; a wider bump
  // would be a sliding (Coulomb) law, which is joint_friction's.
  std::vector<double> grid() const override { return {0.01, 0.015, 0.02, 0.03, 0.045, 0.07, 0.1}; }
  double amplitude(double parameter) const override { return std::exp(parameter); }
  double amplitude_derivative(double parameter) const override { return std::exp(parameter); }
  double parameter_of(double amplitude) const override { return std::log(std::max(amplitude, 1e-3)); }
};

// --- friction_hysteresis: per joint a_j (z_j - sgn(dq_j)), z_j Dahl's state, shared presliding ---
// distance x0. z is integrated along the grid in time order from z = sgn(dq) at its start.
class FrictionHysteresis : public AmplitudesAndShape {
 public:
  std::string name() const override { return "friction_hysteresis"; }
  nlohmann::json describe(const VectorXd& theta) const override {
    return {{"amplitude_Nm", values(theta, 0, kNumJoints)},
            {"presliding_distance_rad", shared_parameter(theta[kNumJoints])}};
  }

 protected:
  std::vector<Vector7> grid_shapes(const Samples& samples, double presliding_distance) const override {
    const std::vector<Vector7>& q = samples.grid_q;
    const std::vector<Vector7>& dq = samples.grid_dq;
    std::vector<Vector7> out(q.size());
    Vector7 z;
    for (int j = 0; j < kNumJoints; ++j) z[j] = q.empty() ? 0.0 : smooth_sign(dq[0][j]);
    for (std::size_t k = 0; k < out.size(); ++k)
      for (int j = 0; j < kNumJoints; ++j) {
        if (k > 0) z[j] = dahl_state(z[j], q[k][j] - q[k - 1][j], presliding_distance);
        out[k][j] = hysteresis_torque(1.0, z[j], dq[k][j]);
      }
    return out;
  }
  // Presliding distances up to a few hundredths of a radian; a longer memory would be a sliding
  // law delayed after each reversal, i.e. joint_friction.
  std::vector<double> grid() const override { return {0.003, 0.005, 0.008, 0.012, 0.02, 0.03, 0.05}; }
};

}  // namespace

double friction_law(double phi1, double phi2, double phi3, double viscous, double dq) {
  return gaz_friction(phi1, phi2, phi3, dq) + viscous * dq;
}

double smooth_sign(double dq) { return std::tanh(dq / kSignVelocity); }

// The plant's Stribeck law (dynamics/friction.hpp) with a smooth sign: measured velocities are
// never exactly zero, where the plant's static friction is set-valued.
double stribeck_excess(double excess, double stribeck_velocity, double dq) {
  return smooth_sign(dq) * stribeck_level(excess, stribeck_velocity, dq);
}

double position_ripple(double a, double b, double period, double q) {
  const double x = 2.0 * M_PI * q / period;
  return a * std::sin(x) + b * std::cos(x);
}

// On a step of constant sign s the Dahl equation dz/dq = (s - z) / x0 is linear: z relaxes to s
// as exp(-|dq| / x0).
double dahl_state(double z, double position_step, double presliding_distance) {
  if (position_step == 0.0) return z;
  const double s = position_step > 0.0 ? 1.0 : -1.0;
  return s + (z - s) * std::exp(-std::abs(position_step) / presliding_distance);
}

double hysteresis_torque(double amplitude, double z, double dq) { return amplitude * (z - smooth_sign(dq)); }

double load_friction(double coefficient, double tau_transmitted, double dq) {
  return coefficient * std::abs(tau_transmitted) * smooth_sign(dq);
}

MatrixXd Effect::jacobian(const Part& part, const VectorXd& theta) const {
  const VectorXd tau = torque(part, theta);
  MatrixXd J(part.rows(), size());
  for (int k = 0; k < size(); ++k) {
    VectorXd moved = theta;
    const double step = 1e-6 * std::max(1.0, std::abs(theta[k]));
    moved[k] += step;
    J.col(k) = (torque(part, moved) - tau) / step;
  }
  return J;
}

VectorXd LinearEffect::torque(const Part& part, const VectorXd& theta) const { return regressor(part) * theta; }
MatrixXd LinearEffect::jacobian(const Part& part, const VectorXd&) const { return regressor(part); }
VectorXd LinearEffect::initial_guess(const Part& part, const VectorXd& target) const {
  return regressor(part).colPivHouseholderQr().solve(target);
}

std::vector<std::unique_ptr<Effect>> effect_library(const Model& model) {
  std::vector<std::unique_ptr<Effect>> library;
  library.push_back(std::make_unique<JointFriction>());
  library.push_back(std::make_unique<SensorOffset>());
  library.push_back(std::make_unique<Payload>(model));
  library.push_back(std::make_unique<Armature>());
  library.push_back(std::make_unique<BaseTilt>());
  library.push_back(std::make_unique<TimeDelay>());
  library.push_back(std::make_unique<InertialParameters>(model));
  library.push_back(std::make_unique<SensorGain>());
  library.push_back(std::make_unique<PositionRipple>());
  library.push_back(std::make_unique<StaticFriction>());
  library.push_back(std::make_unique<FrictionHysteresis>());
  library.push_back(std::make_unique<LoadDependentFriction>());
  library.push_back(std::make_unique<ThermalDrift>());
  return library;
}

std::unique_ptr<Effect> joint_friction_above(const Vector7& viscous_floor) {
  return std::make_unique<JointFriction>(viscous_floor);
}

std::unique_ptr<Effect> physical_inertial_parameters(const Model& model) {
  for (int i = 0; i < kNumJoints; ++i)
    if (!physically_consistent(link_parameters(model.body(i)))) return nullptr;
  return std::make_unique<PhysicalInertialParameters>(model);
}

}  // namespace csp::gap
