// The polynomial scalar (polynomial.hpp): bases are sorted sets whatever order they are spelled
// in, product and union bases hold exactly the right monomials, arithmetic agrees with evaluating
// both sides at random points, and a term outside a basis is refused: at compile time for a
// conversion or an accumulation, at run time (std::domain_error naming the term) for narrow().
#include <array>
#include <random>
#include <type_traits>

#include <catch2/catch.hpp>

#include "kg/retime/dynamics.hpp"
#include "kg/retime/polynomial.hpp"

using namespace kg::retime;
using namespace kg::body;
using Catch::Matchers::Contains;

namespace {

constexpr Monomial x = Monomial::variable(0);
constexpr Monomial y = Monomial::variable(1);
constexpr Monomial z = Monomial::variable(2);
constexpr Monomial one = Monomial::one();

using Linear = Polynomial<SortedBasis<y, x>>;       // spelled out of order on purpose
using Affine = Polynomial<SortedBasis<one, x, z>>;  // 1, x, z

template <class A, class B>
concept AddAssignable = requires(A a, B b) {
  a += b;
};
template <class A, class B>
concept SubtractAssignable = requires(A a, B b) {
  a -= b;
};

template <class P>
P random_polynomial(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-2, 2);
  P p;
  for (double& c : p.c) c = u(rng);
  return p;
}

}  // namespace

TEST_CASE("monomials multiply, order canonically and print") {
  STATIC_REQUIRE((x * x * y).degree() == 3);
  STATIC_REQUIRE((x * y) == (y * x));
  STATIC_REQUIRE(monomial_less(one, x));
  STATIC_REQUIRE(monomial_less(x, y));
  STATIC_REQUIRE(monomial_less(y, x * x));
  STATIC_REQUIRE(monomial_less(x * x, x * y));
  STATIC_REQUIRE(monomial_less(x * y, y * y));
  CHECK((x * x * z).to_string() == "x0^2*x2");
  CHECK(one.to_string() == "1");
  CHECK((path_terms::k * path_terms::pdot2).to_string(kPathVariableNames) == "pdot^2*k");
}

TEST_CASE("bases are sorted sets, products and unions hold exactly the expected monomials") {
  STATIC_REQUIRE(std::is_same_v<SortedBasis<y, x, y>, Basis<x, y>>);
  STATIC_REQUIRE(Linear::size == 2);
  using P = ProductBasis<Linear::BasisType, Linear::BasisType>;
  STATIC_REQUIRE(std::is_same_v<P, Basis<x * x, x * y, y * y>>);
  using U = UnionBasis<Linear::BasisType, Affine::BasisType>;
  STATIC_REQUIRE(std::is_same_v<U, Basis<one, x, y, z>>);
  using Q = ProductBasis<Affine::BasisType, Linear::BasisType>;  // {1, x, z} x {x, y}
  STATIC_REQUIRE(std::is_same_v<Q, SortedBasis<x, y, x * x, x * y, x * z, y * z>>);
  STATIC_REQUIRE(Basis<x, y>::index_of(y) == 1);
  STATIC_REQUIRE(Basis<x, y>::index_of(z) == -1);
  // The path bases of dynamics.hpp.
  STATIC_REQUIRE(PathAcceleration::size == 5);
  STATIC_REQUIRE(PathMassForce::size == 10);
  STATIC_REQUIRE(std::is_same_v<ProductBasis<PathVelocity::BasisType, PathVelocity::BasisType>,
                                Basis<path_terms::pdot2>>);
}

TEST_CASE("arithmetic agrees with evaluation at random points") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int trial = 0; trial < 50; ++trial) {
    const Linear a = random_polynomial<Linear>(rng);
    const Affine b = random_polynomial<Affine>(rng);
    const double s = u(rng);
    const std::array<double, 3> at{u(rng), u(rng), u(rng)};
    const double va = a.evaluate(at), vb = b.evaluate(at);
    CHECK((a + b).evaluate(at) == Approx(va + vb));
    CHECK((a - b).evaluate(at) == Approx(va - vb));
    CHECK((b - a).evaluate(at) == Approx(vb - va));
    CHECK((a * b).evaluate(at) == Approx(va * vb));
    CHECK((b * a * a).evaluate(at) == Approx(vb * va * va));
    CHECK((s * a).evaluate(at) == Approx(s * va));
    CHECK((b * s).evaluate(at) == Approx(s * vb));
    CHECK((-b).evaluate(at) == Approx(-vb));
    Polynomial<UnionBasis<Linear::BasisType, Affine::BasisType>> acc = a;  // widening
    acc += b;
    acc -= a;
    acc *= 2;
    CHECK(acc.evaluate(at) == Approx(2 * vb));
  }
}

TEST_CASE("coefficients are found by monomial, absent monomials read as zero") {
  const Linear p = Linear::term<x>(2.0) + Linear::term<y>(3.0);
  const auto q = p * p;  // 4x² + 12xy + 9y²
  CHECK(q.coefficient<x * x>() == 4);
  CHECK(q.coefficient<x * y>() == 12);
  CHECK(q.coefficient<y * y>() == 9);
  CHECK(q.coefficient(y * y) == 9);
  CHECK(q.coefficient(z) == 0);
  CHECK(q.evaluate(std::array{1.0, 2.0}) == Approx(64));
  CHECK_THROWS_AS(q.evaluate(std::array{1.0}), std::out_of_range);  // y has no value
}

TEST_CASE("a term outside the basis is never dropped") {
  using Squares = Polynomial<SortedBasis<x * x, y * y>>;
  using Product = decltype(Linear{} * Linear{});
  // Compile time: storing x y into a basis without it, or accumulating it, does not compile.
  STATIC_REQUIRE(!std::is_convertible_v<Product, Squares>);
  STATIC_REQUIRE(!std::is_constructible_v<Squares, Product>);
  STATIC_REQUIRE(!AddAssignable<Squares, Product>);
  STATIC_REQUIRE(!SubtractAssignable<Squares, Product>);
  STATIC_REQUIRE(AddAssignable<Product, Squares>);
  STATIC_REQUIRE(std::is_convertible_v<Squares, Product>);
  // A velocity times a velocity is ṗ², which a velocity cannot hold; an acceleration can.
  STATIC_REQUIRE(!std::is_convertible_v<decltype(PathVelocity{} * PathVelocity{}), PathVelocity>);
  STATIC_REQUIRE(std::is_convertible_v<decltype(PathVelocity{} * PathVelocity{}), PathAcceleration>);
  STATIC_REQUIRE(!std::is_convertible_v<decltype(PathAcceleration{} * PathAcceleration{}), PathAcceleration>);
  STATIC_REQUIRE(!std::is_convertible_v<PathMassForce, PathAcceleration>);

  // Run time: narrow() keeps what fits and throws on a non-zero term that does not.
  const Linear p = Linear::term<x>(2.0) + Linear::term<y>(3.0);
  const Product q = p * p;
  CHECK_THROWS_WITH(narrow<Squares>(q), Contains("x0*x1") && Contains("outside the target basis"));
  const Product diagonal = Linear::term<x>(2.0) * Linear::term<x>(1.5);  // 3x², xy and y² zero
  const Squares s = narrow<Squares>(diagonal);
  CHECK(s.coefficient<x * x>() == 3);
  CHECK(s.coefficient<y * y>() == 0);
}
