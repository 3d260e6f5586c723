#pragma once

#include <cmath>

namespace deli {

// Plain 3-vector of doubles; arrays of Vec3 are contiguous xyz triples, the layout the
// pair loop and LAMMPS/OpenMM bridges want.
struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;

  constexpr double& operator[](int a) { return a == 0 ? x : (a == 1 ? y : z); }
  constexpr double operator[](int a) const { return a == 0 ? x : (a == 1 ? y : z); }

  constexpr Vec3& operator+=(const Vec3& o) {
    x += o.x, y += o.y, z += o.z;
    return *this;
  }
  constexpr Vec3& operator-=(const Vec3& o) {
    x -= o.x, y -= o.y, z -= o.z;
    return *this;
  }
  constexpr Vec3& operator*=(double s) {
    x *= s, y *= s, z *= s;
    return *this;
  }
};

constexpr Vec3 operator+(Vec3 a, const Vec3& b) {
  return a += b;
}
constexpr Vec3 operator-(Vec3 a, const Vec3& b) {
  return a -= b;
}
constexpr Vec3 operator-(const Vec3& a) {
  return {-a.x, -a.y, -a.z};
}
constexpr Vec3 operator*(Vec3 a, double s) {
  return a *= s;
}
constexpr Vec3 operator*(double s, Vec3 a) {
  return a *= s;
}
constexpr double dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr double norm2(const Vec3& a) {
  return dot(a, a);
}
inline double norm(const Vec3& a) {
  return std::sqrt(norm2(a));
}

// Symmetric tensor stored as xx, yy, zz, xy, xz, yz (LAMMPS' virial order).
struct SymTensor {
  double xx = 0, yy = 0, zz = 0, xy = 0, xz = 0, yz = 0;

  void add_outer(const Vec3& r, const Vec3& f) {
    xx += r.x * f.x, yy += r.y * f.y, zz += r.z * f.z;
    xy += r.x * f.y, xz += r.x * f.z, yz += r.y * f.z;
  }
  SymTensor& operator+=(const SymTensor& o) {
    xx += o.xx, yy += o.yy, zz += o.zz, xy += o.xy, xz += o.xz, yz += o.yz;
    return *this;
  }
  double trace() const { return xx + yy + zz; }
};

}  // namespace deli
