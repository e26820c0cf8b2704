#pragma once
// Forward-mode automatic differentiation for the implicit tangents (issue 5): a dual number
// a + b eps with eps^2 = 0 carries one directional derivative through any code written on a
// scalar type T. Dual<Dual<double>> carries a second derivative. The element and bond
// kernels are written once on T, so their tangents are exact derivatives of the forces the
// explicit solver uses, not a second hand-derived formula that could drift from them.
#include <Kokkos_Core.hpp>

namespace perishell {

template <class T>
struct Dual {
  T value{};
  T derivative{};

  Dual() = default;
  // A constant: no derivative.
  KOKKOS_INLINE_FUNCTION Dual(double constant) : value(constant), derivative(0.0) {}
  KOKKOS_INLINE_FUNCTION Dual(const T& value_, const T& derivative_) : value(value_), derivative(derivative_) {}
};

namespace math {

KOKKOS_INLINE_FUNCTION double sqrt(double x) { return Kokkos::Experimental::sqrt(x); }
KOKKOS_INLINE_FUNCTION double sin(double x) { return Kokkos::Experimental::sin(x); }
KOKKOS_INLINE_FUNCTION double cos(double x) { return Kokkos::Experimental::cos(x); }
KOKKOS_INLINE_FUNCTION double atan2(double y, double x) { return Kokkos::Experimental::atan2(y, x); }

// The plain number under any nesting of duals, for branches and comparisons.
KOKKOS_INLINE_FUNCTION double valueOf(double x) { return x; }
template <class T>
KOKKOS_INLINE_FUNCTION double valueOf(const Dual<T>& x) {
  return valueOf(x.value);
}

}  // namespace math

template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator-(const Dual<T>& a) {
  return {-a.value, -a.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator+(const Dual<T>& a, const Dual<T>& b) {
  return {a.value + b.value, a.derivative + b.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator-(const Dual<T>& a, const Dual<T>& b) {
  return {a.value - b.value, a.derivative - b.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator*(const Dual<T>& a, const Dual<T>& b) {
  return {a.value * b.value, a.derivative * b.value + a.value * b.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator/(const Dual<T>& a, const Dual<T>& b) {
  const T quotient = a.value / b.value;
  return {quotient, (a.derivative - quotient * b.derivative) / b.value};
}
// Mixed with plain numbers (constants carry no derivative).
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator+(const Dual<T>& a, double b) {
  return {a.value + b, a.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator+(double a, const Dual<T>& b) {
  return {a + b.value, b.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator-(const Dual<T>& a, double b) {
  return {a.value - b, a.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator-(double a, const Dual<T>& b) {
  return {a - b.value, -b.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator*(const Dual<T>& a, double b) {
  return {a.value * b, a.derivative * b};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator*(double a, const Dual<T>& b) {
  return {a * b.value, a * b.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator/(const Dual<T>& a, double b) {
  return {a.value / b, a.derivative / b};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> operator/(double a, const Dual<T>& b) {
  const T quotient = a / b.value;
  return {quotient, -quotient * b.derivative / b.value};
}
template <class T, class U>
KOKKOS_INLINE_FUNCTION Dual<T>& operator+=(Dual<T>& a, const U& b) {
  return a = a + b;
}
template <class T, class U>
KOKKOS_INLINE_FUNCTION Dual<T>& operator-=(Dual<T>& a, const U& b) {
  return a = a - b;
}
template <class T, class U>
KOKKOS_INLINE_FUNCTION Dual<T>& operator*=(Dual<T>& a, const U& b) {
  return a = a * b;
}
template <class T, class U>
KOKKOS_INLINE_FUNCTION Dual<T>& operator/=(Dual<T>& a, const U& b) {
  return a = a / b;
}

namespace math {

template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> sqrt(const Dual<T>& a) {
  const T root = math::sqrt(a.value);
  return {root, a.derivative / (2.0 * root)};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> sin(const Dual<T>& a) {
  return {math::sin(a.value), math::cos(a.value) * a.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> cos(const Dual<T>& a) {
  return {math::cos(a.value), -math::sin(a.value) * a.derivative};
}
template <class T>
KOKKOS_INLINE_FUNCTION Dual<T> atan2(const Dual<T>& y, const Dual<T>& x) {
  return {math::atan2(y.value, x.value), (x.value * y.derivative - y.value * x.derivative) /
                                             (x.value * x.value + y.value * y.value)};
}

}  // namespace math

}  // namespace perishell
