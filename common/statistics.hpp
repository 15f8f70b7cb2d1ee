// Engine-independent statistics over runs.
#pragma once

#include <cstddef>
#include <vector>

namespace gapflow {

struct Summary {
  std::size_t n = 0;
  double mean = 0;
  double sd = 0;           // sample standard deviation (n - 1)
  double ci95_half = 0;    // half-width of the Student-t 95 % interval of the mean
  double lo() const { return mean - ci95_half; }
  double hi() const { return mean + ci95_half; }
};

// Two-sided 97.5 % quantile of Student's t with `df` degrees of freedom.
double student_t_975(std::size_t df);

Summary summarize(const std::vector<double>& values);

}  // namespace gapflow
