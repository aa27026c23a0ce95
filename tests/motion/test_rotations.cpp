#include <catch2/catch.hpp>

#include <random>

#include "kg/motion/rotations.hpp"
#include "motion_test_util.hpp"

using namespace kg::motion;
using kg::motion::test::kPi;

namespace {

const std::vector<std::string> kTaitBryan = {"XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"};
const std::vector<std::string> kProperEuler = {"XYX", "XZX", "YXY", "YZY", "ZXZ", "ZYZ"};

Eigen::Matrix3d angle_axis_product(const std::string& order, const Eigen::Vector3d& a) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (std::size_t i = 0; i < order.size(); ++i)
    R = R *
        Eigen::AngleAxisd(a[static_cast<int>(i)], Eigen::Vector3d::Unit(order[i] - 'X')).toRotationMatrix();
  return R;
}

double max_abs_diff(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return (A - B).cwiseAbs().maxCoeff();
}

}  // namespace

TEST_CASE("rotation orders parse, print and refuse bad text", "[rotations]") {
  const RotationOrder zxy = parse_rotation_order("zXy");
  CHECK(zxy.count == 3);
  CHECK(zxy.axes == std::array<int, 3>{2, 0, 1});
  CHECK(to_string(zxy) == "ZXY");
  CHECK(parse_rotation_order("").count == 0);
  CHECK(to_string(parse_rotation_order("ZXZ")) == "ZXZ");
  CHECK_THROWS_WITH(parse_rotation_order("XYZX"), Catch::Contains("at most 3"));
  CHECK_THROWS_WITH(parse_rotation_order("XAZ"), Catch::Contains("expected letters X, Y, Z"));
  CHECK_THROWS_WITH(parse_rotation_order("XXY"), Catch::Contains("neighbouring"));
  RotationOrder bad;
  bad.count = 2;
  bad.axes = {1, 1, 0};
  CHECK_THROWS_AS(matrix_to_euler(Eigen::Matrix3d::Identity(), bad), std::invalid_argument);
}

TEST_CASE("angles wrap and move by whole turns", "[rotations]") {
  CHECK(wrap_angle(3 * kPi / 2) == Approx(-kPi / 2));
  CHECK(wrap_angle(-kPi) == Approx(kPi));
  CHECK(wrap_angle(kPi) == Approx(kPi));
  CHECK(nearest_angle(-3.0, 3.0) == Approx(-3.0 + 2 * kPi));
  CHECK(nearest_angle(0.25, 0.1) == 0.25);  // bit for bit when already nearest
  CHECK(nearest_angle(0.25, 20 * kPi) == Approx(0.25 + 20 * kPi));
}

TEST_CASE("single axis rotations follow the right-hand rule", "[rotations]") {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  CHECK((axis_rotation(0, kPi / 2) * y - z).norm() < 1e-15);
  CHECK((axis_rotation(1, kPi / 2) * z - x).norm() < 1e-15);
  CHECK((axis_rotation(2, kPi / 2) * x - y).norm() < 1e-15);
  // First listed is outermost: ZX means rotate about X first, then about (fixed) Z.
  const Eigen::Matrix3d R = euler_to_matrix(parse_rotation_order("ZX"), {kPi / 2, kPi / 2, 0});
  CHECK((R * y - z).norm() < 1e-15);  // y -Rx-> z -Rz-> z
  CHECK((R * z - x).norm() < 1e-15);  // z -Rx-> -y -Rz-> +x
}

TEST_CASE("Euler to matrix and quaternion agree with Eigen's angle-axis products", "[rotations]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ang(-2 * kPi, 2 * kPi);
  std::vector<std::string> orders = kTaitBryan;
  orders.insert(orders.end(), kProperEuler.begin(), kProperEuler.end());
  for (std::string o : {"X", "Y", "Z", "XY", "ZX", "YZ", ""}) orders.push_back(o);
  for (const std::string& o : orders) {
    const RotationOrder order = parse_rotation_order(o);
    for (int t = 0; t < 20; ++t) {
      const Eigen::Vector3d a(ang(rng), ang(rng), ang(rng));
      const Eigen::Matrix3d expected = angle_axis_product(o, a);
      INFO("order " << o << " angles " << a.transpose());
      CHECK(max_abs_diff(euler_to_matrix(order, a), expected) < 1e-14);
      CHECK(max_abs_diff(euler_to_quaternion(order, a).toRotationMatrix(), expected) < 1e-14);
    }
  }
}

TEST_CASE("matrix to Euler round trips for all 12 three-axis orders, nearest the reference", "[rotations]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ang(-kPi, kPi), small(-0.3, 0.3);
  std::vector<std::string> orders = kTaitBryan;
  orders.insert(orders.end(), kProperEuler.begin(), kProperEuler.end());
  for (const std::string& o : orders) {
    const RotationOrder order = parse_rotation_order(o);
    for (int t = 0; t < 200; ++t) {
      // Angles anywhere, several turns away from (-pi, pi]: the reference brings them back.
      Eigen::Vector3d a(ang(rng), ang(rng), ang(rng));
      a += 2 * kPi * Eigen::Vector3d(t % 3 - 1, (t / 3) % 3 - 1, 2);
      const Eigen::Matrix3d R = euler_to_matrix(order, a);
      INFO("order " << o << " angles " << a.transpose());
      // With the exact angles (a little off) as reference, they come back.
      const Eigen::Vector3d ref = a + Eigen::Vector3d(small(rng), small(rng), small(rng)) * 0.1;
      CHECK((matrix_to_euler(R, order, ref) - a).cwiseAbs().maxCoeff() < 1e-9);
      // Without a reference: some solution of the same matrix, inside (-pi, pi] per angle.
      const Eigen::Vector3d e = matrix_to_euler(R, order);
      CHECK(max_abs_diff(euler_to_matrix(order, e), R) < 1e-12);
      CHECK(e.cwiseAbs().maxCoeff() <= kPi + 1e-12);
      // The quaternion path gives the same.
      CHECK((quaternion_to_euler(euler_to_quaternion(order, a), order, ref) - a).cwiseAbs().maxCoeff() <
            1e-9);
    }
  }
}

TEST_CASE("the other Euler solution is picked when the reference is nearer it", "[rotations]") {
  const RotationOrder zxy = parse_rotation_order("ZXY");
  const Eigen::Vector3d a(0.4, 0.3, -0.2);
  const Eigen::Vector3d other(0.4 + kPi, kPi - 0.3, -0.2 + kPi);  // same matrix
  const Eigen::Matrix3d R = euler_to_matrix(zxy, a);
  REQUIRE(max_abs_diff(euler_to_matrix(zxy, other), R) < 1e-14);
  CHECK((matrix_to_euler(R, zxy, other + Eigen::Vector3d::Constant(0.05)) - other).norm() < 1e-12);
  CHECK((matrix_to_euler(R, zxy, a - Eigen::Vector3d::Constant(0.05)) - a).norm() < 1e-12);
  const RotationOrder zxz = parse_rotation_order("ZXZ");
  const Eigen::Vector3d p(0.4, 0.3, -0.2), p2(0.4 + kPi, -0.3, -0.2 + kPi);
  REQUIRE(max_abs_diff(euler_to_matrix(zxz, p2), euler_to_matrix(zxz, p)) < 1e-14);
  CHECK((matrix_to_euler(euler_to_matrix(zxz, p), zxz, p2) - p2).norm() < 1e-12);
}

TEST_CASE("gimbal lock: the matrix is kept and the free angle is split towards the reference",
          "[rotations]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ang(-kPi, kPi), small(-0.2, 0.2);
  for (const std::string& o : kTaitBryan) {
    const RotationOrder order = parse_rotation_order(o);
    for (double b : {kPi / 2, -kPi / 2}) {
      for (int t = 0; t < 20; ++t) {
        const Eigen::Vector3d a(ang(rng), b, ang(rng));
        const Eigen::Matrix3d R = euler_to_matrix(order, a);
        INFO("order " << o << " angles " << a.transpose());
        // The reference itself is a solution: it comes back.
        CHECK((matrix_to_euler(R, order, a) - a).norm() < 1e-7);
        // A perturbed reference: still the same matrix, and no farther than the original angles.
        const Eigen::Vector3d ref = a + Eigen::Vector3d(small(rng), 0.0, small(rng));
        const Eigen::Vector3d e = matrix_to_euler(R, order, ref);
        CHECK(max_abs_diff(euler_to_matrix(order, e), R) < 1e-9);
        CHECK((e - ref).norm() <= (a - ref).norm() + 1e-9);
        // Exactly at the lock the outer angles are interchangeable: the split is symmetric.
        CHECK(std::abs(std::abs(e[0] - ref[0]) - std::abs(e[2] - ref[2])) < 1e-7);
      }
    }
  }
  for (const std::string& o : kProperEuler) {
    const RotationOrder order = parse_rotation_order(o);
    for (double b : {0.0, kPi}) {
      const Eigen::Vector3d a(0.7, b, -1.1);
      const Eigen::Matrix3d R = euler_to_matrix(order, a);
      INFO("order " << o << " angles " << a.transpose());
      CHECK((matrix_to_euler(R, order, a) - a).norm() < 1e-7);
      const Eigen::Vector3d e = matrix_to_euler(R, order, {0.5, b, -0.9});
      CHECK(max_abs_diff(euler_to_matrix(order, e), R) < 1e-9);
    }
  }
}

TEST_CASE("near gimbal lock the round trip stays accurate", "[rotations]") {
  for (const std::string& o : kTaitBryan) {
    const RotationOrder order = parse_rotation_order(o);
    for (double eps : {1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
      const Eigen::Vector3d a(0.3, kPi / 2 - eps, -0.6);
      const Eigen::Matrix3d R = euler_to_matrix(order, a);
      INFO("order " << o << " eps " << eps);
      const Eigen::Vector3d e = matrix_to_euler(R, order, a);
      CHECK(max_abs_diff(euler_to_matrix(order, e), R) < 1e-9);
      CHECK((e - a).norm() < 1e-5);
    }
  }
}

TEST_CASE("tracking a rotation through +-180 degrees and gimbal lock gives continuous angles",
          "[rotations]") {
  for (const std::string& o : kTaitBryan) {
    const RotationOrder order = parse_rotation_order(o);
    // Outer angle spins four half turns while the middle one passes through +90 degrees.
    Eigen::Vector3d prev(0, 0, 0);
    double worst_step = 0, worst_error = 0;
    const int steps = 2000;
    for (int i = 0; i <= steps; ++i) {
      const double t = static_cast<double>(i) / steps;
      const Eigen::Vector3d truth(4 * kPi * t, 2.0 * kPi * t, 0.5 - 3 * kPi * t);
      const Eigen::Matrix3d R = euler_to_matrix(order, truth);
      const Eigen::Vector3d e = matrix_to_euler(R, order, prev);
      worst_error = std::max(worst_error, max_abs_diff(euler_to_matrix(order, e), R));
      if (i > 0) worst_step = std::max(worst_step, (e - prev).cwiseAbs().maxCoeff());
      prev = e;
    }
    INFO("order " << o);
    CHECK(worst_error < 1e-9);
    // The truth moves at most 4 pi / 2000 = 0.0063 rad per step; passing the lock exactly
    // can cost a little more on the outer angles, never a jump of pi.
    CHECK(worst_step < 0.1);
  }
}

TEST_CASE("one and two axis orders round trip and project", "[rotations]") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ang(-kPi, kPi);
  for (std::string o : {"X", "Y", "Z", "XY", "XZ", "YX", "YZ", "ZX", "ZY"}) {
    const RotationOrder order = parse_rotation_order(o);
    for (int t = 0; t < 50; ++t) {
      Eigen::Vector3d a(ang(rng), ang(rng), 0);
      if (order.count == 1) a[1] = 0;
      INFO("order " << o << " angles " << a.transpose());
      const Eigen::Vector3d ref = a + Eigen::Vector3d(0.1, -0.1, 0) + Eigen::Vector3d(4 * kPi, -2 * kPi, 0);
      const Eigen::Vector3d e = matrix_to_euler(euler_to_matrix(order, a), order, ref);
      const Eigen::Vector3d expected = a + Eigen::Vector3d(4 * kPi, order.count == 2 ? -2 * kPi : 0, 0);
      CHECK((e - expected).norm() < 1e-9);
    }
  }
  // One axis: the twist about it of a rotation that also swings.
  for (const Eigen::Matrix3d& R : {Eigen::Matrix3d(axis_rotation(0, 0.3) * axis_rotation(1, 0.7)),
                                   Eigen::Matrix3d(axis_rotation(1, 0.7) * axis_rotation(2, -0.4))}) {
    const Eigen::Vector3d e = matrix_to_euler(R, parse_rotation_order("Y"));
    CHECK(e[0] == Approx(0.7).margin(1e-12));  // a swing about a perpendicular axis leaves the twist
    CHECK(e[1] == 0);
  }
  // Two axes: R's image of the second axis is matched exactly.
  const Eigen::Matrix3d S = euler_to_matrix(parse_rotation_order("XYZ"), {0.4, -0.5, 0.05});
  const Eigen::Vector3d f = matrix_to_euler(S, parse_rotation_order("XY"));
  const Eigen::Matrix3d P = euler_to_matrix(parse_rotation_order("XY"), f);
  CHECK((P.col(1) - S.col(1)).norm() < 0.06);
  CHECK(f[0] == Approx(0.4).margin(0.05));
  CHECK(f[1] == Approx(-0.5).margin(0.05));
  CHECK(matrix_to_euler(S, parse_rotation_order("")).isZero());
}

TEST_CASE("slerp takes the shorter arc at constant speed", "[rotations]") {
  const Eigen::Quaterniond a(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()));
  // 350 degrees about Y the long way is 10 degrees the short way; -q is the same rotation.
  const Eigen::Quaterniond b(Eigen::AngleAxisd(0.2 + 350.0 * kPi / 180, Eigen::Vector3d::UnitY()));
  for (const Eigen::Quaterniond& bb : {b, Eigen::Quaterniond(-b.coeffs())}) {
    for (double u : {0.0, 0.25, 0.5, 1.0}) {
      const Eigen::Quaterniond q = slerp_shortest(a, bb, u);
      const Eigen::Quaterniond expected(
          Eigen::AngleAxisd(0.2 - u * 10.0 * kPi / 180, Eigen::Vector3d::UnitY()));
      CHECK(q.angularDistance(expected) < 1e-12);
      CHECK(q.norm() == Approx(1.0));
    }
  }
}
