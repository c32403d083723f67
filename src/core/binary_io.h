// A minimal binary record format for checkpoints: values are written in the machine's own
// representation (a checkpoint is resumed on the machine, or at least the architecture, that
// wrote it; the header records the byte order and the sizes so a foreign file is refused).
// Every block starts with a four-letter tag, so a truncated or shuffled file is detected
// where it goes wrong, not later as a wrong number.
#pragma once
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.h"
#include "core/vec2.h"

namespace demlab {

class BinaryWriter {
public:
    template <typename T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        const char* p = reinterpret_cast<const char*>(&v);
        buf_.append(p, sizeof(T));
    }
    void put(const Vec2& v) {
        put(v.x());
        put(v.y());
    }
    void put(const std::string& s) {
        put(uint64_t(s.size()));
        buf_.append(s);
    }
    template <typename T>
    void put(const std::vector<T>& v) {
        put(uint64_t(v.size()));
        for (const T& x : v) put(x);
    }
    void tag(const char (&t)[5]) { buf_.append(t, 4); }
    const std::string& bytes() const { return buf_; }

private:
    std::string buf_;
};

class BinaryReader {
public:
    BinaryReader(std::string bytes, std::string source) : buf_(std::move(bytes)), source_(std::move(source)) {}

    template <typename T>
    void get(T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        need(sizeof(T));
        std::memcpy(&v, buf_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
    }
    void get(Vec2& v) {
        double x, y;
        get(x);
        get(y);
        v = Vec2(x, y);
    }
    void get(std::string& s) {
        uint64_t n;
        get(n);
        need(n);
        s.assign(buf_.data() + pos_, n);
        pos_ += n;
    }
    // expected: the length the caller knows (SIZE_MAX: any)
    template <typename T>
    void get(std::vector<T>& v, size_t expected = SIZE_MAX) {
        uint64_t n;
        get(n);
        if (expected != SIZE_MAX && n != expected)
            throw InputError(source_ + ": corrupt checkpoint (a list of " + std::to_string(n) + " entries where " +
                             std::to_string(expected) + " were expected)");
        need(n);  // at least one byte per entry: refuses absurd lengths before allocating
        v.resize(n);
        for (T& x : v) get(x);
    }
    template <typename T>
    T get() {
        T v;
        get(v);
        return v;
    }
    void expect_tag(const char (&t)[5]) {
        need(4);
        if (std::memcmp(buf_.data() + pos_, t, 4) != 0)
            throw InputError(source_ + ": corrupt checkpoint (block '" + std::string(t) + "' expected at byte " +
                             std::to_string(pos_) + ")");
        pos_ += 4;
    }
    bool at_end() const { return pos_ == buf_.size(); }

private:
    void need(uint64_t n) const {
        if (n > buf_.size() - pos_)
            throw InputError(source_ + ": truncated checkpoint (" + std::to_string(buf_.size()) + " bytes)");
    }
    std::string buf_;
    std::string source_;
    size_t pos_ = 0;
};

}  // namespace demlab
