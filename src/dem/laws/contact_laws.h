// The contact laws the engine knows, registered in one place: the list RegisteredLaws below.
// A law is a type with the members LinearLaw has (linear_law.h, contact_law_part.h lists them):
// its parameters and keys, its checks, its tables, its history, its force, its share of the
// step and of the ledger. The world keeps one material table per registered law and runs its
// force pass, ledger and time step as templates over the law a scenario chose (contact.law),
// dispatched here once per pass, never per contact.
//
// Adding a law: its header under dem/laws/ and its type in RegisteredLaws. Its kind is its
// place in the list, its contact.law name its kName, its keys its section's.
#pragma once
#include <cstddef>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "dem/laws/debris_law.h"
#include "dem/laws/hertz_law.h"
#include "dem/laws/linear_law.h"

namespace demlab {

using RegisteredLaws = std::tuple<LinearLaw, DebrisLaw, HertzLaw>;

// A law's kind: its index in RegisteredLaws (the first, the linear law, is the default).
enum class ContactLawKind : int {};

template <typename Law, size_t I = 0>
constexpr ContactLawKind law_kind() {
    static_assert(I < std::tuple_size_v<RegisteredLaws>, "not a registered law (contact_laws.h)");
    if constexpr (std::is_same_v<Law, std::tuple_element_t<I, RegisteredLaws>>) return ContactLawKind(int(I));
    else return law_kind<Law, I + 1>();
}

// Calls f(Law{}) for the law of `kind` and returns what it returns.
template <size_t I = 0, typename F>
decltype(auto) with_contact_law(ContactLawKind kind, F&& f) {
    if constexpr (I + 1 < std::tuple_size_v<RegisteredLaws>) {
        if (int(kind) != int(I)) return with_contact_law<I + 1>(kind, std::forward<F>(f));
    }
    return f(std::tuple_element_t<I, RegisteredLaws>{});
}

// Calls f(Law{}) for every registered law, in the list's order.
template <typename F>
void for_each_contact_law(F&& f) {
    std::apply([&](auto... law) { (f(law), ...); }, RegisteredLaws{});
}

// contact.law's name of a kind
inline const char* law_name(ContactLawKind kind) {
    return with_contact_law(kind, [](auto law) { return decltype(law)::kName; });
}

// A law's parameters per pair of the discs' materials ([mi * nm + mj], nm: World::disc_materials_)
// and per disc material and wall ([mi * nw + w], from the wall's own material).
template <typename Law>
struct LawTables {
    std::vector<typename Law::Params> disc_disc, disc_wall;
};

template <typename Tuple>
struct LawTablesOf;
template <typename... Laws>
struct LawTablesOf<std::tuple<Laws...>> {
    using tables = std::tuple<LawTables<Laws>...>;
    using defs = std::tuple<typename Laws::Def...>;
};
// every registered law's tables (only the chosen law's are filled)
using AllLawTables = typename LawTablesOf<RegisteredLaws>::tables;
// every registered law's own definition (the keys of its section; LinearLaw's is empty: it
// reads the materials and the damping)
using AllLawDefs = typename LawTablesOf<RegisteredLaws>::defs;

}  // namespace demlab
