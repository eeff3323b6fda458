// Small dense linear systems (the patch wrench's 6 x 6, a squeeze's up to 13 x 13).
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>

namespace rg {

// Solve m[:size, :size] x = rhs[:size] into out by Gaussian elimination with partial
// pivoting (m and rhs are overwritten); false for a (near-)singular matrix: a pivot at or
// below `singular` times the largest diagonal entry.
template <int N>
bool solve_dense(double (&m)[N][N], double* rhs, int size, double* out, double singular) {
    double largest = 0.0;
    for (int i = 0; i < size; ++i) {
        largest = std::max(largest, std::fabs(m[i][i]));
    }
    if (largest == 0.0) {
        return false;
    }
    for (int col = 0; col < size; ++col) {
        int pivot = col;
        for (int row = col + 1; row < size; ++row) {
            if (std::fabs(m[row][col]) > std::fabs(m[pivot][col])) {
                pivot = row;
            }
        }
        if (std::fabs(m[pivot][col]) <= singular * largest) {
            return false;
        }
        if (pivot != col) {
            for (int k = 0; k < size; ++k) {
                std::swap(m[col][k], m[pivot][k]);
            }
            std::swap(rhs[col], rhs[pivot]);
        }
        for (int row = col + 1; row < size; ++row) {
            const double f = m[row][col] / m[col][col];
            for (int k = col; k < size; ++k) {
                m[row][k] -= f * m[col][k];
            }
            rhs[row] -= f * rhs[col];
        }
    }
    for (int row = size - 1; row >= 0; --row) {
        double acc = rhs[row];
        for (int k = row + 1; k < size; ++k) {
            acc -= m[row][k] * out[k];
        }
        out[row] = acc / m[row][row];
    }
    return true;
}

}  // namespace rg
