// Anderson acceleration on a slowly contracting linear fixed point: it converges in far fewer
// steps than the plain iteration, and a cleared history starts over.
#include "qs/core/anderson.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>

namespace {

// G(x) = M x + b with M symmetric, eigenvalues in [0.5, 0.99]: the plain iteration's error shrinks
// by 0.99 per step.
struct Linear {
  Eigen::MatrixXd m;
  Eigen::VectorXd b, fixed;
  explicit Linear(int n) : m(n, n), b(n) {
    Eigen::MatrixXd q = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) q(i, j) = std::sin(1.0 + i * 7 + j * 3);
    const Eigen::MatrixXd basis = Eigen::HouseholderQR<Eigen::MatrixXd>(q).householderQ();
    Eigen::VectorXd eig(n);
    for (int i = 0; i < n; ++i) eig[i] = 0.5 + 0.49 * i / (n - 1);
    m = basis * eig.asDiagonal() * basis.transpose();
    for (int i = 0; i < n; ++i) b[i] = std::cos(0.3 * i);
    fixed = (Eigen::MatrixXd::Identity(n, n) - m).lu().solve(b);
  }
  Eigen::VectorXd g(const Eigen::VectorXd& x) const { return m * x + b; }
};

int steps_to(const Linear& p, bool accelerate, double tolerance) {
  qs::Anderson aa(5);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(p.b.size());
  for (int k = 1; k <= 5000; ++k) {
    const Eigen::VectorXd g = p.g(x);
    x = accelerate && aa.step(g, g - x) ? aa.next() : g;
    if ((x - p.fixed).norm() < tolerance * p.fixed.norm()) return k;
  }
  return 5000;
}

}  // namespace

TEST(Anderson, ConvergesFarFasterThanThePlainIteration) {
  const Linear p(20);
  const int plain = steps_to(p, false, 1e-8), accelerated = steps_to(p, true, 1e-8);
  // Measured: 1810 plain steps (0.99^k < 1e-8), 92 accelerated.
  EXPECT_GT(plain, 1000);
  EXPECT_LT(accelerated, 200);
}

TEST(Anderson, FirstStepAfterClearIsThePlainOne) {
  const Linear p(4);
  qs::Anderson aa(3);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(4);
  Eigen::VectorXd g = p.g(x);
  EXPECT_FALSE(aa.step(g, g - x));
  x = g;
  g = p.g(x);
  EXPECT_TRUE(aa.step(g, g - x));
  aa.clear();
  x = aa.next();
  g = p.g(x);
  EXPECT_FALSE(aa.step(g, g - x));
}
