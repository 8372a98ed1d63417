// franka::Errors (libfranka's struct: each flag a reference into the array it owns, so copying
// must rebind nothing and copy the array) and CSP's ErrorSet.
#include "csp/rt/errors.hpp"

namespace franka {

// Each member refers to its own slot of errors_: X-list order = array order.
#define CSP_BIND(name) , name(errors_[static_cast<std::size_t>(csp::rt::Error::name)])

Errors::Errors() : errors_{} CSP_FRANKA_ERRORS(CSP_BIND) {}
Errors::Errors(const Errors& other) : errors_(other.errors_) CSP_FRANKA_ERRORS(CSP_BIND) {}
Errors::Errors(const std::array<bool, 41>& errors) : errors_(errors) CSP_FRANKA_ERRORS(CSP_BIND) {}

#undef CSP_BIND

Errors& Errors::operator=(Errors other) {
  errors_ = other.errors_;
  return *this;
}

Errors::operator bool() const noexcept { return static_cast<bool>(csp::rt::ErrorSet(errors_)); }

Errors::operator std::string() const { return static_cast<std::string>(csp::rt::ErrorSet(errors_)); }

std::ostream& operator<<(std::ostream& ostream, const Errors& errors) {
  return ostream << csp::rt::ErrorSet(errors);
}

}  // namespace franka

namespace csp::rt {

const char* error_name(Error error) {
  switch (error) {
#define CSP_NAME_CASE(name) \
  case Error::name: return #name;
    CSP_FRANKA_ERRORS(CSP_NAME_CASE)
#undef CSP_NAME_CASE
  }
  return "unknown_error";
}

ErrorSet::ErrorSet(const franka::Errors& errors) {
#define CSP_READ(name) flags_[static_cast<int>(Error::name)] = errors.name;
  CSP_FRANKA_ERRORS(CSP_READ)
#undef CSP_READ
}

ErrorSet::operator bool() const noexcept {
  for (bool e : flags_)
    if (e) return true;
  return false;
}

ErrorSet::operator std::string() const {
  std::string out = "[";
  for (int i = 0; i < kNumErrors; ++i) {
    if (!flags_[i]) continue;
    if (out.size() > 1) out += ", ";
    out += error_name(static_cast<Error>(i));
  }
  return out + "]";
}

bool has(const franka::Errors& errors, Error error) { return ErrorSet(errors).has(error); }

std::ostream& operator<<(std::ostream& out, const ErrorSet& errors) {
  out << '[';
  bool first = true;
  for (int i = 0; i < kNumErrors; ++i) {
    if (!errors.flags()[i]) continue;
    out << (first ? "" : ",") << '"' << error_name(static_cast<Error>(i)) << '"';
    first = false;
  }
  return out << ']';
}

}  // namespace csp::rt
