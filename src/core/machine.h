// What machine a figure was measured on: the processor as Linux names it, the CPUs this
// process may use, and CPU 0's caches. `bench` and summary.json print it beside every speed,
// because machines of the same kind differ: an AMD EPYC (Zen 4) and an Intel Xeon (family 6,
// model 207) with the same core count run DB-9k a third apart (docs/performance.md).
#pragma once
#include <cstddef>
#include <string>

namespace demlab {

struct MachineInfo {
    std::string cpu;          // "model name" of /proc/cpuinfo's first processor ("" if not listed)
    std::string vendor;       // its "vendor_id" (GenuineIntel, AuthenticAMD; "" if not listed)
    int family = -1;          // "cpu family" (-1 if not listed)
    int model = -1;           // "model" (-1 if not listed)
    unsigned cpus = 0;        // CPUs the process may run on (0 if unknown)
    size_t l2_bytes = 0;      // bytes, CPU 0's level-2 cache (0 if not listed)
    size_t largest_cache_bytes = 0;  // bytes, CPU 0's largest cache (0 if none listed)
};

// The first processor's fields from the text of /proc/cpuinfo (the fields it lacks stay unset).
MachineInfo parse_cpuinfo(const std::string& text);

// A cache size as /sys/devices/system/cpu/cpu0/cache/index*/size gives it ("48K", "2048K",
// "307200K", "32M" or plain bytes), in bytes; 0 when it does not read as one.
size_t parse_cache_size(const std::string& text);

// This machine, read once (/proc/cpuinfo, /sys, the scheduler's CPU mask).
const MachineInfo& machine_info();

// One line: "Intel(R) Xeon(R) Processor (GenuineIntel, family 6, model 207), 2 CPUs, L2 2 MB,
// largest cache 300 MB".
std::string machine_summary(const MachineInfo& m);

}  // namespace demlab
