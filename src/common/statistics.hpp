#pragma once
// Sample statistics of an ensemble's results (src/solver/ensemble_report.cpp): mean, standard
// deviation, standard error and the 95 % confidence interval of the mean from Student's t
// distribution (its quantile by bisection on the regularised incomplete beta function, so that no
// statistics library is needed and every machine prints the same digits).
#include <vector>

namespace fdem::stats {

struct Summary {
  long n = 0;
  double mean = 0, sd = 0, se = 0;  // sd: with n - 1; se = sd / sqrt(n); both 0 for n < 2
  double ci_low = 0, ci_high = 0;   // mean -/+ t(0.975, n - 1) se (the mean itself for n < 2)
  double min = 0, max = 0;
};

// The sample's summary; the values are taken in the order given (sums in that order, so the same
// values in the same order give the same bits). An empty sample gives n = 0 and zeros.
Summary summarise(const std::vector<double>& x);

// The regularised incomplete beta function I_x(a, b), a, b > 0, x in [0, 1].
double incomplete_beta(double a, double b, double x);
// Student's t distribution with nu > 0 degrees of freedom: P(T <= t).
double student_t_cdf(double t, double nu);
// Its quantile: the t with P(T <= t) = p, p in (0, 1).
double student_t_quantile(double p, double nu);

}  // namespace fdem::stats
