#include "scenario/fingerprint.h"

#include <cstdint>
#include <cstdio>
#include <sstream>

#include "core/error.h"
#include "core/fileio.h"

namespace demlab {

namespace {

struct FileKey {
    const char* key;
    const std::string& (*path)(const Scenario&);
};

// every key that names a file (test Reuse.EveryFileKeyIsHashed holds the registry to it)
const FileKey kFileKeys[] = {
    {"terrain.profile", [](const Scenario& s) -> const std::string& { return s.terrain.profile; }},
    {"terrain.grid", [](const Scenario& s) -> const std::string& { return s.terrain.grid; }},
    {"lattice_release.top", [](const Scenario& s) -> const std::string& { return s.lattice_release.top; }},
    {"release.from_file", [](const Scenario& s) -> const std::string& { return s.release.from_file; }},
    {"dan.sync_front", [](const Scenario& s) -> const std::string& { return s.dan.sync_front; }},
    {"dem3.terrain", [](const Scenario& s) -> const std::string& { return s.dem3.terrain; }},
    {"dem3.release_top", [](const Scenario& s) -> const std::string& { return s.dem3.release_top; }},
};

// 128-bit FNV-1a in two 64-bit words (prime 2^88 + 0x13B, offset basis 6c62272e...c58d)
class Fnv1a128 {
public:
    void add(const char* p, size_t n) {
        for (size_t k = 0; k < n; ++k) {
            lo_ ^= uint8_t(p[k]);
            multiply();
        }
    }
    void add(const std::string& s) { add(s.data(), s.size()); }
    std::string hex() const {
        char out[33];
        std::snprintf(out, sizeof out, "%016llx%016llx", (unsigned long long)hi_, (unsigned long long)lo_);
        return out;
    }

private:
    // (hi, lo) *= 2^88 + 0x13B, modulo 2^128
    void multiply() {
        constexpr uint64_t c = 0x13B;
        const uint64_t a = (lo_ & 0xFFFFFFFFu) * c, b = (lo_ >> 32) * c;  // lo * c = a + b 2^32
        const uint64_t low = a + (b << 32);
        const uint64_t high = (b >> 32) + (((a >> 32) + (b & 0xFFFFFFFFu)) >> 32);
        hi_ = hi_ * c + high + (lo_ << 24);  // lo 2^88 reaches the high word shifted by 24
        lo_ = low;
    }
    uint64_t hi_ = 0x6c62272e07bb0142ULL, lo_ = 0x62b821756295c58dULL;
};


}  // namespace

std::string scenario_settings(const std::string& text) {
    std::istringstream in(text);
    std::string line, out;
    while (std::getline(in, line))
        if (line.empty() || line[0] != '#') out += line + '\n';
    return out;
}

const std::vector<std::string>& scenario_file_keys() {
    static const std::vector<std::string> keys = [] {
        std::vector<std::string> k;
        for (const FileKey& f : kFileKeys) k.push_back(f.key);
        return k;
    }();
    return keys;
}

std::string content_hash(const std::string& bytes) {
    Fnv1a128 h;
    h.add(bytes);
    return h.hex();
}

std::vector<ScenarioInput> scenario_inputs(const Scenario& s) {
    std::vector<ScenarioInput> out;
    for (const FileKey& f : kFileKeys) {
        const std::string& path = f.path(s);
        if (path.empty()) continue;
        out.push_back({f.key, path, content_hash(read_input_file(path, kMaxTableBytes, std::string("input file (") + f.key + ")"))});
    }
    return out;
}

std::string scenario_fingerprint(const Scenario& s, const std::vector<ScenarioInput>& inputs) {
    Fnv1a128 h;
    h.add("demlab scenario fingerprint 1\n");
    h.add(scenario_settings(resolved_toml(s)));
    for (const ScenarioInput& in : inputs) {
        h.add("\n[input] " + in.key + " = " + in.path + "\n");
        h.add(in.hash);
    }
    return h.hex();
}

std::string scenario_fingerprint(const Scenario& s) { return scenario_fingerprint(s, scenario_inputs(s)); }

}  // namespace demlab
