// Random test data drawn in one order whatever the compiler.
//
// The arguments of a call are evaluated in an unspecified order: GCC 12 evaluates the last one
// first, clang 14 the first one, so Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)) built
// different data under the two compilers, and four tests decided differently in the clang build of
// .ci/run's hardening stage than in the README's GCC build. Tests draw several values of one
// expression through DrawLastFirst, or into named values one statement each, in the order GCC gave
// the data the tests' figures were measured on: the last argument first. (The library's simulators
// draw through core/simulation/portable_random.h, which is sequenced the same way for the same
// reason.)
#ifndef PHOTOPOSE_TESTS_SUPPORT_ORDERED_DRAWS_H_
#define PHOTOPOSE_TESTS_SUPPORT_ORDERED_DRAWS_H_

#include <Eigen/Core>

namespace photopose {

// An N-vector whose component i is draw(i), the calls made for i = N-1, ..., 1, 0 in that order.
template <int N, typename Draw>
Eigen::Matrix<double, N, 1> DrawLastFirst(Draw&& draw) {
  Eigen::Matrix<double, N, 1> value;
  for (int i = N - 1; i >= 0; --i) value[i] = draw(i);
  return value;
}

}  // namespace photopose

#endif  // PHOTOPOSE_TESTS_SUPPORT_ORDERED_DRAWS_H_
