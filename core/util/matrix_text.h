// Matrices as a course copies them: plain text (one row per line, columns aligned) and LaTeX
// (a bmatrix), each entry with a given number of significant digits, so that K, R, t and F
// can be pasted into notes or slides.
#pragma once

#include <string>

#include <Eigen/Core>

namespace facet {

// Rows on separate lines, entries right-aligned in columns (each as wide as its widest entry),
// separated by two spaces; each entry as printf's "%.*g" with `significant` digits (1 to 17), "-0" written
// "0". No trailing newline. An empty matrix gives "".
std::string MatrixToText(const Eigen::Ref<const Eigen::MatrixXd>& matrix, int significant = 8);

// "\begin{bmatrix} a & b \\ c & d \end{bmatrix}" with the same entries, an exponent written
// "1.5 \times 10^{-7}"; rows on separate lines.
std::string MatrixToLatex(const Eigen::Ref<const Eigen::MatrixXd>& matrix, int significant = 8);

}  // namespace facet
