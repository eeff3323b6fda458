// Small dense linear systems (the patch wrench's 6 x 6, a squeeze's up to 13 x 13).
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>

namespace rg {

// Factor m[:size, :size] in place by Gaussian elimination with partial pivoting: the upper
// triangle holds U, the entries below the diagonal the multipliers of L, pivot[col] the row
// swapped into row col. false for a (near-)singular matrix: a pivot at or below `singular`
// times the largest diagonal entry. A factored matrix solves any number of right-hand sides
// (solve_factored) with exactly the arithmetic of solving each from scratch: the contact
// passes of a step solve one patch's system with a new right-hand side each (patch.cpp).
template <int N>
bool factor_dense(double (&m)[N][N], int size, int* pivot, double singular) {
    double largest = 0.0;
    for (int i = 0; i < size; ++i) {
        largest = std::max(largest, std::fabs(m[i][i]));
    }
    if (largest == 0.0) {
        return false;
    }
    for (int col = 0; col < size; ++col) {
        int p = col;
        for (int row = col + 1; row < size; ++row) {
            if (std::fabs(m[row][col]) > std::fabs(m[p][col])) {
                p = row;
            }
        }
        if (std::fabs(m[p][col]) <= singular * largest) {
            return false;
        }
        pivot[col] = p;
        if (p != col) {
            for (int k = 0; k < size; ++k) {
                std::swap(m[col][k], m[p][k]);
            }
        }
        for (int row = col + 1; row < size; ++row) {
            const double f = m[row][col] / m[col][col];
            for (int k = col + 1; k < size; ++k) {
                m[row][k] -= f * m[col][k];
            }
            m[row][col] = f;  // below the diagonal: L's multiplier (U's entry there is 0)
        }
    }
    return true;
}

// Solve the factored system (factor_dense) for rhs[:size] into out (rhs is overwritten).
template <int N>
void solve_factored(const double (&m)[N][N], const int* pivot, int size, double* rhs,
                    double* out) {
    // the row swaps first: each swap in factor_dense moved the multipliers found so far with
    // their rows, so every entry then meets its own multipliers in the order elimination made
    // them, as when the swaps and eliminations alternate
    for (int col = 0; col < size; ++col) {
        if (pivot[col] != col) {
            std::swap(rhs[col], rhs[pivot[col]]);
        }
    }
    for (int col = 0; col < size; ++col) {
        for (int row = col + 1; row < size; ++row) {
            rhs[row] -= m[row][col] * rhs[col];
        }
    }
    for (int row = size - 1; row >= 0; --row) {
        double acc = rhs[row];
        for (int k = row + 1; k < size; ++k) {
            acc -= m[row][k] * out[k];
        }
        out[row] = acc / m[row][row];
    }
}

// Solve m[:size, :size] x = rhs[:size] into out (m and rhs are overwritten); false for a
// (near-)singular matrix (factor_dense).
template <int N>
bool solve_dense(double (&m)[N][N], double* rhs, int size, double* out, double singular) {
    int pivot[N];
    if (!factor_dense(m, size, pivot, singular)) {
        return false;
    }
    solve_factored(m, pivot, size, rhs, out);
    return true;
}

}  // namespace rg
