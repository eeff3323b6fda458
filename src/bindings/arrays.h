// numpy arrays in and out of the core: checked reads into Arrays, views over the core's own
// buffers, and copies handed to Python.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include "base/span.h"

namespace rg {

namespace nb = nanobind;

template <class T>
using InArray = nb::ndarray<const T, nb::c_contig, nb::device::cpu>;

// A numpy array over `count` rows of T starting at `data` (T holds `width` scalars of S), kept
// alive by owner. shape: the numpy shape.
template <class S, class T>
nb::ndarray<nb::numpy, S> view(nb::handle owner, T* data, std::initializer_list<size_t> shape) {
    return nb::ndarray<nb::numpy, S>(reinterpret_cast<S*>(data), shape, owner);
}

// Python owns a copy of `values` as a numpy array of this shape.
template <class S>
nb::ndarray<nb::numpy, S> hand_over(std::vector<S>&& values, std::initializer_list<size_t> shape) {
    auto* owned = new std::vector<S>(std::move(values));
    nb::capsule owner(owned, [](void* p) noexcept { delete static_cast<std::vector<S>*>(p); });
    return nb::ndarray<nb::numpy, S>(owned->data(), shape, owner);
}

// The rows of a C-contiguous array of scalars S whose trailing shape is `row_shape` (T is
// laid out as that many S), as an Array<T>; `what` names the array in the error.
template <class T, class S>
Array<T> read_rows(const InArray<S>& a, std::initializer_list<size_t> row_shape, const char* what) {
    size_t width = 1;
    for (size_t d : row_shape) {
        width *= d;
    }
    const size_t trailing = row_shape.size();
    bool ok = a.ndim() == trailing + 1 || (a.size() == 0 && a.ndim() >= 1);
    if (ok && a.size() != 0) {
        size_t k = 1;
        for (size_t d : row_shape) {
            ok = ok && a.shape(k++) == d;
        }
    }
    if (!ok || sizeof(T) != width * sizeof(S)) {
        throw nb::value_error((std::string("rigid_gym core: ") + what +
                               " has the wrong shape for its rows").c_str());
    }
    Array<T> out;
    out.assign(reinterpret_cast<const T*>(a.data()), static_cast<int64_t>(a.size() / width));
    return out;
}

}  // namespace rg
