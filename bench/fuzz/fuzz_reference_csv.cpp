// libFuzzer target: read_reference_csv (an imported reference) on arbitrary text. It must return
// a reference that passes its own validation, or throw InvalidArgument naming the problem; a
// crash, a hang, another exception type or a sanitizer report is a finding.
// Build and run: bench/fuzz/run.sh (command and results in bench/README.md).
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <cstdint>
#include <sstream>
#include <string>

namespace {
using saltus::MatT;
using saltus::VecT;
// Only the sizes matter to the import: a planar point mass (nq = 2) pushed by two forces (nu = 2)
// above a frictionless floor.
class PushedMass {
 public:
  static constexpr int nq = 2, nu = 2, nc = 1;
  static constexpr const char* name = "pushed_mass";
  const saltus::ContactSpec& contact(int) const { return floor_; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const { return MatT<T, nq, nq>::Identity(); }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const { return VecT<T, nq>(T(0), T(9.81)); }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const { return MatT<T, nq, nu>::Identity(); }
  template <class T>
  T gap(int, const VecT<T, nq>& q) const { return q[1]; }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const { return VecT<T, 2>(q[0], T(0)); }

 private:
  saltus::ContactSpec floor_{"floor"};
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const auto ref = saltus::read_reference_csv<PushedMass>(in);
    ref.validate();
  } catch (const saltus::InvalidArgument&) {
  }
  return 0;
}
