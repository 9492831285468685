#include "core/util/matrix_text.h"

#include <algorithm>
#include <cassert>
#include <cstdio>
#include <vector>

namespace facet {
namespace {

std::string Entry(double x, int significant) {
  if (x == 0.0) x = 0.0;  // -0 prints as "-0"
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, x);
  return buffer;
}

std::string LatexEntry(double x, int significant) {
  const std::string text = Entry(x, significant);
  const size_t e = text.find_first_of("eE");
  if (e == std::string::npos) return text;
  // "1.5e-07" -> "1.5 \times 10^{-7}": drop the exponent's '+' and leading zeros.
  const std::string mantissa = text.substr(0, e);
  std::string exponent = text.substr(e + 1);
  bool negative = false;
  if (!exponent.empty() && (exponent[0] == '+' || exponent[0] == '-')) {
    negative = exponent[0] == '-';
    exponent.erase(0, 1);
  }
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return mantissa + " \\times 10^{" + (negative ? "-" : "") + exponent + "}";
}

}  // namespace

std::string MatrixToText(const Eigen::Ref<const Eigen::MatrixXd>& matrix, int significant) {
  assert(significant >= 1 && significant <= 17 && "MatrixToText: 1 to 17 significant digits");
  std::vector<std::string> entries;
  std::vector<size_t> width(matrix.cols(), 0);
  for (Eigen::Index r = 0; r < matrix.rows(); ++r)
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) {
      entries.push_back(Entry(matrix(r, c), significant));
      width[c] = std::max(width[c], entries.back().size());
    }
  std::string out;
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    if (r > 0) out += '\n';
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) {
      const std::string& e = entries[r * matrix.cols() + c];
      if (c > 0) out += "  ";
      out += std::string(width[c] - e.size(), ' ') + e;
    }
  }
  return out;
}

std::string MatrixToLatex(const Eigen::Ref<const Eigen::MatrixXd>& matrix, int significant) {
  assert(significant >= 1 && significant <= 17 && "MatrixToLatex: 1 to 17 significant digits");
  std::string out = "\\begin{bmatrix}\n";
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) {
      if (c > 0) out += " & ";
      out += LatexEntry(matrix(r, c), significant);
    }
    out += r + 1 < matrix.rows() ? " \\\\\n" : "\n";
  }
  return out + "\\end{bmatrix}";
}

}  // namespace facet
