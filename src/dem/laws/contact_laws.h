// The contact laws the engine knows, registered in one place. A law is a type with the
// members LinearLaw has (linear_law.h); the world keeps one material table per registered law
// and runs its force pass, ledger and time step as templates over the law a scenario chose
// (contact.law), dispatched here once per pass, never per contact.
//
// Adding a law: its header under dem/laws/, a ContactLawKind value, a case in
// with_contact_law, its type in RegisteredLaws, and its name in the contact.law key.
#pragma once
#include <tuple>
#include <vector>

#include "dem/laws/debris_law.h"
#include "dem/laws/linear_law.h"

namespace demlab {

enum class ContactLawKind { Linear, Debris };

using RegisteredLaws = std::tuple<LinearLaw, DebrisLaw>;

// Calls f(Law{}) for the law of `kind` and returns what it returns.
template <typename F>
decltype(auto) with_contact_law(ContactLawKind kind, F&& f) {
    switch (kind) {
        case ContactLawKind::Linear: break;
        case ContactLawKind::Debris: return f(DebrisLaw{});
    }
    return f(LinearLaw{});
}

// A law's parameters per pair of materials ([mi * nm + mj]) and per material and wall ([mi * nw + w]).
template <typename Law>
struct LawTables {
    std::vector<typename Law::Params> disc_disc, disc_wall;
};

template <typename Tuple>
struct LawTablesOf;
template <typename... Laws>
struct LawTablesOf<std::tuple<Laws...>> {
    using type = std::tuple<LawTables<Laws>...>;
};
// every registered law's tables (only the chosen law's are filled)
using AllLawTables = typename LawTablesOf<RegisteredLaws>::type;

}  // namespace demlab
