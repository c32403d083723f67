// libFuzzer target over scenario parsing and validation: any input must either give a scenario
// or an InputError naming what is wrong. Anything else (another exception, a crash, a hang, a
// sanitizer report) is a defect. Run: scripts/fuzz.sh [RUNS]
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "scenario/scenario.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        demlab::Scenario s = demlab::parse_scenario(text, "fuzz.toml");
        // the first line, read as an override, exercises --set too
        const std::string first = text.substr(0, text.find('\n'));
        if (first.find('=') != std::string::npos) demlab::apply_override(s, first);
        demlab::finish_scenario(s);
        const std::string resolved = demlab::resolved_toml(s);
        demlab::parse_scenario(resolved, "resolved.toml");  // what we write must read back
    } catch (const demlab::InputError&) {
        // a clear refusal is the expected answer to bad input
    }
    return 0;
}
