// Array arguments of the core's functions on caller-owned numpy buffers (winding_number,
// rasterize, lowest_centres, ...): each one checked for its dtype, C order, writability and
// shape before any is touched, with an error that names the function, the argument and what
// was expected. Inputs are never converted or copied (an output copied would silently drop
// what is written into it), so the caller's arrays are exactly what the core reads and writes.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <initializer_list>
#include <string>
#include <type_traits>

#include "base/span.h"

namespace rg {

namespace nb = nanobind;

// A C-contiguous numpy array of S on the CPU; const S for arrays that are only read.
template <class S>
using ArrayArg = nb::ndarray<S, nb::c_contig, nb::device::cpu>;

namespace arg_text {

template <class S>
const char* dtype_name() {
    using T = std::remove_const_t<S>;
    if constexpr (std::is_same_v<T, double>) {
        return "float64";
    } else if constexpr (std::is_same_v<T, int32_t>) {
        return "int32";
    } else if constexpr (std::is_same_v<T, int64_t>) {
        return "int64";
    } else {
        static_assert(std::is_same_v<T, uint8_t>, "arrays are float64, int32, int64 or uint8");
        return "uint8";
    }
}

// "(any, 3)"-style text of a shape; a free extent (-1) is written "any".
template <class Extents>
std::string shape_text(const Extents& extents) {
    std::string text = "(";
    size_t k = 0;
    for (auto e : extents) {
        text += (k++ > 0 ? ", " : "") + (e < 0 ? std::string("any") : std::to_string(e));
    }
    return text + (k == 1 ? ",)" : ")");
}

// What `value` is, for an error message: its type, or an array's layout, dtype and shape.
inline std::string describe(nb::handle value) {
    nb::ndarray<nb::ro> any;
    if (!nb::try_cast(value, any, false)) {
        return std::string("an object of type ") + nb::type_name(value.type()).c_str();
    }
    std::string kind;
    nb::ndarray<> writable;
    if (!nb::try_cast(value, writable, false)) {
        kind += "read-only ";
    }
    nb::ndarray<nb::ro, nb::c_contig> ordered;
    if (!nb::try_cast(value, ordered, false)) {
        kind += "non-C-contiguous ";
    }
    std::string text = (kind.empty() ? "an " : "a ") + kind + "array";
    if (nb::hasattr(value, "dtype")) {
        const nb::object dtype = value.attr("dtype");
        text += std::string(" of dtype ") + nb::str(nb::handle(dtype)).c_str() + " and";
    }
    std::string shape = "(";
    for (size_t k = 0; k < any.ndim(); ++k) {
        shape += (k > 0 ? ", " : "") + std::to_string(any.shape(k));
    }
    return text + " shape " + shape + (any.ndim() == 1 ? ",)" : ")");
}

}  // namespace arg_text

// `value` as an array of S with this shape (extents -1 are free), or TypeError (not a
// C-contiguous array of S, or read-only for a non-const S) or ValueError (another shape).
// `where` names the argument: "function: argument".
template <class S>
ArrayArg<S> array_arg(nb::handle value, const char* where, std::initializer_list<int64_t> shape) {
    ArrayArg<S> a;
    if (!nb::try_cast(value, a, false)) {
        const std::string expected = std::string("a C-contiguous ") +
                                     (std::is_const_v<S> ? "" : "writable ") +
                                     "numpy array of dtype " + arg_text::dtype_name<S>() +
                                     " and shape " + arg_text::shape_text(shape);
        throw nb::type_error(
            (std::string(where) + " must be " + expected + ", got " + arg_text::describe(value))
                .c_str());
    }
    bool ok = a.ndim() == shape.size();
    size_t k = 0;
    for (int64_t e : shape) {
        ok = ok && (e < 0 || static_cast<int64_t>(a.shape(k)) == e);
        k += 1;
    }
    if (!ok) {
        throw nb::value_error((std::string(where) + " must have shape " +
                               arg_text::shape_text(shape) + ", got " +
                               arg_text::describe(value))
                                  .c_str());
    }
    return a;
}

// The extent of dimension k of `a`, signed.
template <class S>
int64_t extent(const ArrayArg<S>& a, size_t k) {
    return static_cast<int64_t>(a.shape(k));
}

// The array's scalars as rows of T (T laid out as a whole number of S, e.g. Vec3 as 3 doubles).
template <class T, class S>
Span<T> rows(const ArrayArg<S>& a) {
    static_assert(sizeof(T) % sizeof(S) == 0, "a row must be a whole number of scalars");
    return {reinterpret_cast<T*>(a.data()),
            static_cast<int64_t>(a.size() / (sizeof(T) / sizeof(S)))};
}

// ValueError unless every entry of `indices` lies in [low, high); `what` says what they index.
template <class I>
void check_indices(Span<const I> indices, int64_t low, int64_t high, const char* where,
                   const char* what) {
    for (int64_t k = 0; k < indices.size; ++k) {
        const int64_t i = indices[k];
        if (i < low || i >= high) {
            throw nb::value_error((std::string(where) + " holds " + std::to_string(i) +
                                   " at flat index " + std::to_string(k) + ", outside [" +
                                   std::to_string(low) + ", " + std::to_string(high) + ") (" +
                                   what + ")")
                                      .c_str());
        }
    }
}

}  // namespace rg
