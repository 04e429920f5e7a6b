// The scene-free part of prediction_check.hpp.
#include <saltus/sensitivity/prediction_check.hpp>

#include <cmath>

namespace saltus {

double fitted_log_slope(const std::vector<double>& x, const std::vector<double>& y) {
  SALTUS_REQUIRE(x.size() == y.size() && x.size() >= 2, "fitted_log_slope: ", x.size(), " x and ",
                y.size(), " y values (at least 2 pairs needed)");
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double lx = std::log(x[k]), ly = std::log(y[k]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

std::vector<double> default_prediction_eps() { return {1e-2, 1e-3, 1e-4, 1e-5, 1e-6}; }

}  // namespace saltus
