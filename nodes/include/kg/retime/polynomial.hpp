// A polynomial scalar over a compile-time basis of monomials, so that one inverse dynamics code
// (rnea.hpp) computes either numbers or the coefficients of the generalised forces as functions
// of the retiming's ṗ², p̈, the gravity vector and a segment's mass scale (McCann et al. 2006
// §3.1: "we replaced the standard double data type with a custom generic polynomial type").
//
// The basis is part of the type, so every product is exact by construction: Polynomial<A> times
// Polynomial<B> is a Polynomial<ProductBasis<A, B>> holding every product monomial, and a sum is
// a Polynomial over the union of the bases. Storing a polynomial into a type whose basis lacks
// one of its monomials does not compile (the BasisIncludes constraint); narrow<Target>(p) is the
// one explicit way down and throws std::domain_error when a dropped coefficient is not zero. No
// term is ever lost silently.
//
// Cheap arithmetic: coefficients are a std::array<double, N> in the basis' order; a product by a
// double is N multiplications, and a product of polynomials runs over a multiplication table
// computed at compile time (no search, no allocation). Quantities carry only the monomials they
// can have (a velocity along the path is a multiple of ṗ alone: one coefficient).
//
//   enum : int { kX = 0, kY = 1 };                        // variable indices, 0..kMaxVariables-1
//   constexpr Monomial x = Monomial::variable(kX), y = Monomial::variable(kY);
//   using Linear = Polynomial<SortedBasis<x, y>>;         // a x + b y
//   Linear p = Linear::term<x>(2.0) + Linear::term<y>(3.0);
//   auto q = p * p;                                       // Polynomial over {x², xy, y²}
//   double v = q.evaluate(std::array{1.0, 2.0});         // (2 + 6)² = 64
//   double c = q.coefficient<x * y>();                    // 12
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace kg::retime {

inline constexpr int kMaxVariables = 8;

// x_0^p_0 x_1^p_1 ... x_7^p_7 (powers up to 255). A structural type: usable as a template argument.
struct Monomial {
  std::array<std::uint8_t, kMaxVariables> power{};

  // x_v^p.
  static constexpr Monomial variable(int v, int p = 1) {
    Monomial m;
    m.power[static_cast<std::size_t>(v)] = static_cast<std::uint8_t>(p);
    return m;
  }
  // The constant 1.
  static constexpr Monomial one() { return Monomial{}; }

  constexpr int degree() const {
    int d = 0;
    for (std::uint8_t p : power) d += p;
    return d;
  }
  constexpr Monomial operator*(const Monomial& o) const {
    Monomial m;
    for (std::size_t i = 0; i < power.size(); ++i)
      m.power[i] = static_cast<std::uint8_t>(power[i] + o.power[i]);
    return m;
  }
  constexpr bool operator==(const Monomial&) const = default;

  // "x0^2*x3" (the constant: "1"), or with names per variable: "pdot^2*k".
  std::string to_string(std::span<const char* const> names = {}) const {
    std::string s;
    for (std::size_t i = 0; i < power.size(); ++i) {
      if (power[i] == 0) continue;
      if (!s.empty()) s.push_back('*');
      if (i < names.size()) {
        s.append(names[i]);
      } else {
        s.push_back('x');
        s.append(std::to_string(i));
      }
      if (power[i] > 1) {
        s.push_back('^');
        s.append(std::to_string(power[i]));
      }
    }
    return s.empty() ? "1" : s;
  }
};

// The canonical order of monomials in a basis: by degree, then with higher powers of
// lower-numbered variables first (x² < xy < y²).
constexpr bool monomial_less(const Monomial& a, const Monomial& b) {
  if (a.degree() != b.degree()) return a.degree() < b.degree();
  for (std::size_t i = 0; i < a.power.size(); ++i)
    if (a.power[i] != b.power[i]) return a.power[i] > b.power[i];
  return false;
}

namespace detail {

template <std::size_t N>
constexpr bool strictly_ordered(const std::array<Monomial, N>& m) {
  for (std::size_t i = 1; i < N; ++i)
    if (!monomial_less(m[i - 1], m[i])) return false;
  return true;
}

}  // namespace detail

// A set of monomials in canonical order (monomial_less, no repeats: a Basis spelled otherwise
// does not compile; SortedBasis sorts for you).
template <Monomial... Ms>
struct Basis {
  static constexpr std::size_t size = sizeof...(Ms);
  static constexpr std::array<Monomial, sizeof...(Ms)> monomials{Ms...};
  static_assert(
      detail::strictly_ordered(monomials),
      "kg::retime::Basis: monomials must be in monomial_less order without repeats (use SortedBasis)");

  // Position of m in the basis, -1 when absent.
  static constexpr int index_of(const Monomial& m) {
    for (std::size_t i = 0; i < size; ++i)
      if (monomials[i] == m) return static_cast<int>(i);
    return -1;
  }
  static constexpr bool contains(const Monomial& m) { return index_of(m) >= 0; }
};

namespace detail {

// A sorted, repeat-free list of at most N monomials: a structural value to build Basis types from.
template <std::size_t N>
struct MonomialSet {
  std::array<Monomial, N> m{};
  std::size_t n = 0;
};

template <std::size_t N>
constexpr MonomialSet<N> sorted_set(std::array<Monomial, N> all) {
  std::sort(all.begin(), all.end(), monomial_less);
  MonomialSet<N> s;
  for (std::size_t i = 0; i < N; ++i)
    if (s.n == 0 || !(s.m[s.n - 1] == all[i])) s.m[s.n++] = all[i];
  return s;
}

template <auto Set, std::size_t... I>
Basis<Set.m[I]...> basis_of(std::index_sequence<I...>);

template <auto Set>
using BasisOf = decltype(basis_of<Set>(std::make_index_sequence<Set.n>()));

template <class A, class B>
constexpr auto union_set() {
  std::array<Monomial, A::size + B::size> all{};
  for (std::size_t i = 0; i < A::size; ++i) all[i] = A::monomials[i];
  for (std::size_t i = 0; i < B::size; ++i) all[A::size + i] = B::monomials[i];
  return sorted_set(all);
}

template <class A, class B>
constexpr auto product_set() {
  std::array<Monomial, A::size * B::size> all{};
  for (std::size_t i = 0; i < A::size; ++i)
    for (std::size_t j = 0; j < B::size; ++j) all[i * B::size + j] = A::monomials[i] * B::monomials[j];
  return sorted_set(all);
}

template <Monomial... Ms>
constexpr auto listed_set() {
  return sorted_set(std::array<Monomial, sizeof...(Ms)>{Ms...});
}

}  // namespace detail

// The basis of the listed monomials, sorted, repeats merged.
template <Monomial... Ms>
using SortedBasis = detail::BasisOf<detail::listed_set<Ms...>()>;
// Every monomial of A or of B.
template <class A, class B>
using UnionBasis = detail::BasisOf<detail::union_set<A, B>()>;
// Every product of a monomial of A and one of B.
template <class A, class B>
using ProductBasis = detail::BasisOf<detail::product_set<A, B>()>;

// True when every monomial of Small is in Big.
template <class Big, class Small>
constexpr bool basis_includes() {
  for (const Monomial& m : Small::monomials)
    if (!Big::contains(m)) return false;
  return true;
}
template <class Big, class Small>
concept BasisIncludes = basis_includes<Big, Small>();

template <class B>
class Polynomial {
 public:
  using BasisType = B;
  static constexpr std::size_t size = B::size;

  // Coefficients in the basis' order (B::monomials). Plain data.
  std::array<double, size> c{};

  constexpr Polynomial() = default;
  // Widening: a polynomial over a sub-basis. Does not compile when B lacks a monomial of B2.
  template <class B2>
  requires BasisIncludes<B, B2>
  constexpr Polynomial(const Polynomial<B2>& p) {  // NOLINT: implicit on purpose
    if constexpr (std::is_same_v<B, B2>) {
      c = p.c;
    } else {
      for (std::size_t i = 0; i < B2::size; ++i) c[static_cast<std::size_t>(kIndexFrom<B2>[i])] = p.c[i];
    }
  }

  // coefficient * M; M must be in the basis (compile-time check).
  template <Monomial M>
  static constexpr Polynomial term(double coefficient) {
    static_assert(B::contains(M), "kg::retime::Polynomial::term: monomial outside the basis");
    Polynomial p;
    p.c[static_cast<std::size_t>(B::index_of(M))] = coefficient;
    return p;
  }

  // The coefficient of M; M must be in the basis (compile-time check).
  template <Monomial M>
  constexpr double coefficient() const {
    static_assert(B::contains(M), "kg::retime::Polynomial::coefficient: monomial outside the basis");
    return c[static_cast<std::size_t>(B::index_of(M))];
  }
  // The coefficient of m; 0 for a monomial outside the basis (the type says it cannot occur).
  constexpr double coefficient(const Monomial& m) const {
    const int i = B::index_of(m);
    return i < 0 ? 0.0 : c[static_cast<std::size_t>(i)];
  }

  // The value at variables x (x[v] is variable v; variables beyond x.size() must not occur).
  double evaluate(std::span<const double> x) const {
    double sum = 0;
    for (std::size_t i = 0; i < size; ++i) {
      double t = c[i];
      for (std::size_t v = 0; v < static_cast<std::size_t>(kMaxVariables); ++v)
        for (int p = 0; p < B::monomials[i].power[v]; ++p) {
          if (v >= x.size())
            throw std::out_of_range("Polynomial::evaluate: variable " + std::to_string(v) +
                                    " has no value (" + std::to_string(x.size()) + " given)");
          t *= x[v];
        }
      sum += t;
    }
    return sum;
  }

  template <class B2>
  requires BasisIncludes<B, B2>
  constexpr Polynomial& operator+=(const Polynomial<B2>& p) {
    for (std::size_t i = 0; i < B2::size; ++i) c[static_cast<std::size_t>(kIndexFrom<B2>[i])] += p.c[i];
    return *this;
  }
  template <class B2>
  requires BasisIncludes<B, B2>
  constexpr Polynomial& operator-=(const Polynomial<B2>& p) {
    for (std::size_t i = 0; i < B2::size; ++i) c[static_cast<std::size_t>(kIndexFrom<B2>[i])] -= p.c[i];
    return *this;
  }
  constexpr Polynomial& operator*=(double s) {
    for (double& x : c) x *= s;
    return *this;
  }
  constexpr Polynomial operator-() const {
    Polynomial r;
    for (std::size_t i = 0; i < size; ++i) r.c[i] = -c[i];
    return r;
  }

 private:
  template <class B2>
  static constexpr std::array<int, B2::size> index_from() {
    std::array<int, B2::size> idx{};
    for (std::size_t i = 0; i < B2::size; ++i) idx[i] = B::index_of(B2::monomials[i]);
    return idx;
  }
  // Where each coefficient of a Polynomial<B2> goes in this basis.
  template <class B2>
  static constexpr std::array<int, B2::size> kIndexFrom = index_from<B2>();
};

template <class A, class B>
constexpr Polynomial<UnionBasis<A, B>> operator+(const Polynomial<A>& a, const Polynomial<B>& b) {
  if constexpr (std::is_same_v<A, B>) {
    Polynomial<A> r;
    for (std::size_t i = 0; i < A::size; ++i) r.c[i] = a.c[i] + b.c[i];
    return r;
  } else {
    Polynomial<UnionBasis<A, B>> r(a);
    r += b;
    return r;
  }
}

template <class A, class B>
constexpr Polynomial<UnionBasis<A, B>> operator-(const Polynomial<A>& a, const Polynomial<B>& b) {
  if constexpr (std::is_same_v<A, B>) {
    Polynomial<A> r;
    for (std::size_t i = 0; i < A::size; ++i) r.c[i] = a.c[i] - b.c[i];
    return r;
  } else {
    Polynomial<UnionBasis<A, B>> r(a);
    r -= b;
    return r;
  }
}

template <class B>
constexpr Polynomial<B> operator*(const Polynomial<B>& a, double s) {
  Polynomial<B> r;
  for (std::size_t i = 0; i < B::size; ++i) r.c[i] = a.c[i] * s;
  return r;
}
template <class B>
constexpr Polynomial<B> operator*(double s, const Polynomial<B>& a) {
  return a * s;
}

namespace detail {

// table[i][j]: where monomial i of A times monomial j of B lands in ProductBasis<A, B>.
template <class A, class B>
constexpr auto product_table() {
  using P = ProductBasis<A, B>;
  std::array<std::array<int, (B::size > 0 ? B::size : 1)>, (A::size > 0 ? A::size : 1)> t{};
  for (std::size_t i = 0; i < A::size; ++i)
    for (std::size_t j = 0; j < B::size; ++j) t[i][j] = P::index_of(A::monomials[i] * B::monomials[j]);
  return t;
}
template <class A, class B>
inline constexpr auto kProductTable = product_table<A, B>();

}  // namespace detail

// The exact product: every monomial of the result's basis kept.
template <class A, class B>
constexpr Polynomial<ProductBasis<A, B>> operator*(const Polynomial<A>& a, const Polynomial<B>& b) {
  Polynomial<ProductBasis<A, B>> r;
  for (std::size_t i = 0; i < A::size; ++i)
    for (std::size_t j = 0; j < B::size; ++j)
      r.c[static_cast<std::size_t>(detail::kProductTable<A, B>[i][j])] += a.c[i] * b.c[j];
  return r;
}

// The same polynomial over a smaller basis, for when the caller knows some terms vanish. Throws
// std::domain_error naming the first monomial outside Target's basis whose coefficient is not
// exactly zero: terms are never dropped silently.
template <class Target, class B>
Polynomial<typename Target::BasisType> narrow(const Polynomial<B>& p) {
  using T = typename Target::BasisType;
  Polynomial<T> r;
  for (std::size_t i = 0; i < B::size; ++i) {
    const int k = T::index_of(B::monomials[i]);
    if (k >= 0) {
      r.c[static_cast<std::size_t>(k)] = p.c[i];
    } else if (p.c[i] != 0.0) {
      throw std::domain_error("kg::retime::narrow: the term " + std::to_string(p.c[i]) + " * " +
                              B::monomials[i].to_string() + " is outside the target basis");
    }
  }
  return r;
}

}  // namespace kg::retime
