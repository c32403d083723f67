#include "core/machine.h"

#include <sched.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

namespace demlab {

namespace {

std::string trim(const std::string& s) {
    size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return s.substr(a, b - a);
}

int to_int(const std::string& s) {
    int v = -1;
    return std::sscanf(s.c_str(), "%d", &v) == 1 && v >= 0 ? v : -1;
}

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string size_text(size_t bytes) {
    char b[32];
    if (bytes >= (size_t(1) << 20) && bytes % (size_t(1) << 20) == 0) std::snprintf(b, sizeof b, "%zu MB", bytes >> 20);
    else std::snprintf(b, sizeof b, "%zu KB", bytes >> 10);
    return b;
}

}  // namespace

MachineInfo parse_cpuinfo(const std::string& text) {
    MachineInfo m;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        const std::string t = trim(line);
        if (t.empty()) {
            if (!m.cpu.empty() || !m.vendor.empty()) break;  // the first processor's block has ended
            continue;
        }
        const size_t colon = t.find(':');
        if (colon == std::string::npos) continue;
        const std::string key = trim(t.substr(0, colon)), value = trim(t.substr(colon + 1));
        if (key == "model name" && m.cpu.empty()) m.cpu = value;
        else if (key == "vendor_id" && m.vendor.empty()) m.vendor = value;
        else if (key == "cpu family" && m.family < 0) m.family = to_int(value);
        else if (key == "model" && m.model < 0) m.model = to_int(value);
    }
    return m;
}

size_t parse_cache_size(const std::string& text) {
    const std::string t = trim(text);
    size_t digits = 0;
    while (digits < t.size() && std::isdigit(static_cast<unsigned char>(t[digits]))) ++digits;
    if (digits == 0 || digits > 12) return 0;
    const size_t value = std::stoull(t.substr(0, digits));
    const std::string unit = t.substr(digits);
    const int shift = unit.empty() ? 0 : unit == "K" ? 10 : unit == "M" ? 20 : unit == "G" ? 30 : -1;
    if (shift < 0 || value > (SIZE_MAX >> shift)) return 0;  // not a size, or beyond size_t
    return value << shift;
}

const MachineInfo& machine_info() {
    static const MachineInfo info = [] {
        MachineInfo m = parse_cpuinfo(read_text("/proc/cpuinfo"));
        cpu_set_t set;
        CPU_ZERO(&set);
        m.cpus = sched_getaffinity(0, sizeof set, &set) == 0 ? unsigned(CPU_COUNT(&set)) : std::thread::hardware_concurrency();
        for (int index = 0; index < 8; ++index) {
            const std::string dir = "/sys/devices/system/cpu/cpu0/cache/index" + std::to_string(index) + "/";
            const size_t size = parse_cache_size(read_text(dir + "size"));
            if (size == 0) continue;
            m.largest_cache_bytes = std::max(m.largest_cache_bytes, size);
            if (trim(read_text(dir + "level")) == "2") m.l2_bytes = size;
        }
        return m;
    }();
    return info;
}

std::string machine_summary(const MachineInfo& m) {
    std::string s = m.cpu.empty() ? "an unnamed processor" : m.cpu;
    if (!m.vendor.empty() || m.family >= 0 || m.model >= 0) {
        s += " (";
        std::string inner = m.vendor;
        if (m.family >= 0) inner += (inner.empty() ? "" : ", ") + std::string("family ") + std::to_string(m.family);
        if (m.model >= 0) inner += (inner.empty() ? "" : ", ") + std::string("model ") + std::to_string(m.model);
        s += inner + ")";
    }
    if (m.cpus > 0) s += ", " + std::to_string(m.cpus) + (m.cpus == 1 ? " CPU" : " CPUs");
    if (m.l2_bytes > 0) s += ", L2 " + size_text(m.l2_bytes);
    if (m.largest_cache_bytes > 0) s += ", largest cache " + size_text(m.largest_cache_bytes);
    return s;
}

}  // namespace demlab
