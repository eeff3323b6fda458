// Span: a pointer and a length, indexed like an array, bounds-checked in checked builds.
//
// Every buffer the step reads or writes is reached through a Span (or a row of one), so a
// checked build (CMake option RIGID_GYM_CHECKED, on in the sanitizer build) catches an index
// out of range where it happens instead of corrupting a neighbour's memory. A failed check
// throws (the bindings turn it into a Python exception) rather than aborting the interpreter.
// In ordinary builds the check compiles away.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace rg {

#ifdef RIGID_GYM_CHECKED
[[noreturn]] inline void fail_check(const char* what, const char* file, int line) {
    throw std::out_of_range(std::string("rigid_gym core check failed: ") + what + " at " +
                            file + ":" + std::to_string(line));
}
#define RG_CHECK(condition) \
    ((condition) ? static_cast<void>(0) : ::rg::fail_check(#condition, __FILE__, __LINE__))
#else
#define RG_CHECK(condition) static_cast<void>(0)
#endif

template <class T>
struct Span {
    T* data = nullptr;
    int64_t size = 0;

    T& operator[](int64_t i) const {
        RG_CHECK(i >= 0 && i < size);
        return data[i];
    }

    // The elements [first, first + count).
    Span sub(int64_t first, int64_t count) const {
        RG_CHECK(first >= 0 && count >= 0 && first + count <= size);
        return {data + first, count};
    }
};

// Array: an owning buffer (a std::vector) with the same checked indexing.
template <class T>
class Array {
public:
    Array() = default;
    explicit Array(int64_t count, const T& value = T()) : items_(count, value) {}

    T& operator[](int64_t i) {
        RG_CHECK(i >= 0 && i < size());
        return items_[i];
    }
    const T& operator[](int64_t i) const {
        RG_CHECK(i >= 0 && i < size());
        return items_[i];
    }
    int64_t size() const { return static_cast<int64_t>(items_.size()); }
    T* data() { return items_.data(); }
    const T* data() const { return items_.data(); }
    void assign(int64_t count, const T& value) { items_.assign(count, value); }
    void assign(const T* first, int64_t count) { items_.assign(first, first + count); }
    Span<T> span() { return {items_.data(), size()}; }
    Span<const T> span() const { return {items_.data(), size()}; }
    // Rows [first, first + count) as a Span, e.g. one world's rows of a batched buffer.
    Span<T> rows(int64_t first, int64_t count) { return span().sub(first, count); }
    Span<const T> rows(int64_t first, int64_t count) const { return span().sub(first, count); }

private:
    std::vector<T> items_;
};

}  // namespace rg

// A table of a struct's rows lists each row once as X(type, name, rows per world, fill), so
// that the struct of one world's Spans, the batch's Arrays, their allocation and their views
// are all written from it (solver/world.h). These expand an entry into a member.
#define RG_SPAN_FIELD(type, name, count, fill) ::rg::Span<type> name;
#define RG_CONST_SPAN_FIELD(type, name, count, fill) ::rg::Span<const type> name;
#define RG_ARRAY_FIELD(type, name, count, fill) ::rg::Array<type> name;
#define RG_POINTER_FIELD(type, name, count, fill) type* name;  // rows 1: one value per world
