// The machine a figure was measured on (machine.h): what bench and summary.json print.
#include <gtest/gtest.h>

#include "core/fileio.h"
#include "core/machine.h"

using namespace demlab;

namespace {
// the first two processors of an Intel Xeon machine of this project (/proc/cpuinfo, cut)
const char* const kXeon =
    "processor\t: 0\n"
    "vendor_id\t: GenuineIntel\n"
    "cpu family\t: 6\n"
    "model\t\t: 207\n"
    "model name\t: Intel(R) Xeon(R) Processor\n"
    "stepping\t: 2\n"
    "cpu MHz\t\t: 2100.000\n"
    "\n"
    "processor\t: 1\n"
    "vendor_id\t: SomeoneElse\n"
    "cpu family\t: 25\n"
    "model\t\t: 17\n"
    "model name\t: Not the first one\n";
}  // namespace

TEST(Machine, ReadsTheFirstProcessorOfCpuinfo) {
    const MachineInfo m = parse_cpuinfo(kXeon);
    EXPECT_EQ(m.cpu, "Intel(R) Xeon(R) Processor");
    EXPECT_EQ(m.vendor, "GenuineIntel");
    EXPECT_EQ(m.family, 6);
    EXPECT_EQ(m.model, 207);
    // "model name" must not be taken for "model"
    EXPECT_EQ(parse_cpuinfo("model name\t: X\nmodel\t\t: 1\n").model, 1);
    EXPECT_EQ(parse_cpuinfo("model name\t: X\nmodel\t\t: 1\n").cpu, "X");
}

TEST(Machine, LeavesWhatCpuinfoLacksUnset) {
    for (const char* text : {"", "\n\n", "garbage without colons\n", "cpu family\t: many\n"}) {
        const MachineInfo m = parse_cpuinfo(text);
        EXPECT_EQ(m.cpu, "") << text;
        EXPECT_EQ(m.family, -1) << text;
        EXPECT_EQ(m.model, -1) << text;
    }
    EXPECT_EQ(machine_summary(MachineInfo{}), "an unnamed processor");
}

TEST(Machine, ReadsCacheSizesAsLinuxWritesThem) {
    EXPECT_EQ(parse_cache_size("48K\n"), size_t(48) << 10);
    EXPECT_EQ(parse_cache_size("2048K"), size_t(2) << 20);
    EXPECT_EQ(parse_cache_size("307200K\n"), size_t(300) << 20);
    EXPECT_EQ(parse_cache_size("32M"), size_t(32) << 20);
    EXPECT_EQ(parse_cache_size("4096"), size_t(4096));
    for (const char* bad : {"", "K", "12X", "-4K", "12 K", "9999999999999K"}) EXPECT_EQ(parse_cache_size(bad), 0u) << bad;
    // a size beyond size_t is no size, not a wrapped-around one
    EXPECT_EQ(parse_cache_size("999999999999G"), 0u);
    EXPECT_EQ(parse_cache_size("99999999999G"), 0u);
    EXPECT_EQ(parse_cache_size("999999999999M"), size_t(999999999999) << 20);  // still fits
}

TEST(Machine, SummaryNamesProcessorCpusAndCaches) {
    MachineInfo m = parse_cpuinfo(kXeon);
    m.cpus = 2;
    m.l2_bytes = size_t(2) << 20;
    m.largest_cache_bytes = size_t(300) << 20;
    EXPECT_EQ(machine_summary(m),
              "Intel(R) Xeon(R) Processor (GenuineIntel, family 6, model 207), 2 CPUs, L2 2 MB, largest cache 300 MB");
    m.l2_bytes = 1536 << 10;
    m.cpus = 1;
    EXPECT_EQ(machine_summary(m),
              "Intel(R) Xeon(R) Processor (GenuineIntel, family 6, model 207), 1 CPU, L2 1536 KB, largest cache 300 MB");
}

TEST(Machine, ThisMachineHasACpu) {
    const MachineInfo& m = machine_info();
    EXPECT_GE(m.cpus, 1u);
    EXPECT_FALSE(machine_summary(m).empty());
}

TEST(Machine, SummaryGoesIntoJsonEscaped) {
    // summary.json writes the line as a JSON string (json_string, fileio.h)
    EXPECT_EQ(json_string("Intel(R) Xeon(R) Processor"), "\"Intel(R) Xeon(R) Processor\"");
    EXPECT_EQ(json_string("a \"quoted\" C:\\cpu"), "\"a \\\"quoted\\\" C:\\\\cpu\"");
    EXPECT_EQ(json_string(std::string("tab\tnl\n") + char(1)), "\"tab\\u0009nl\\u000a\\u0001\"");
    EXPECT_EQ(json_string(""), "\"\"");
}
