// Closed lists of names, declared once (STYLE.md, practice 12). A choice
// enum (the accumulation filter, the denoiser, ...) is one X-macro list of
// X(enumerator, "name") from which the enum, the name of each value, the
// parser and the list of names all come:
//
//   #define LUXEL_FILTER_CHOICES(X) X(kBox, "box") X(kGaussian, "gaussian")
//   LUXEL_CHOICE_ENUM(Filter, LUXEL_FILTER_CHOICES)
//
// declares `enum class Filter { kBox, kGaussian }`, and then
//   choice_name(Filter::kGaussian)   "gaussian"
//   parse_choice<Filter>("box")      Filter::kBox; std::nullopt for other text
//   choice_list<Filter>()            {"box", "gaussian"}: a settings schema's
//                                    .choices, so help, `luxel settings
//                                    --json`, the proto translation and docs
//                                    list the names in this order
// Enumerators are numbered in list order.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#define LUXEL_CHOICE_ENUMERATOR_(id, name) id,
#define LUXEL_CHOICE_NAME_(id, name) name,

// At namespace scope. The names are found through luxel_choice_names(E{}),
// by argument-dependent lookup in E's namespace.
#define LUXEL_CHOICE_ENUM(E, LIST)                                                     \
  enum class E { LIST(LUXEL_CHOICE_ENUMERATOR_) };                                     \
  inline constexpr const char* const kChoiceNamesOf##E[] = {LIST(LUXEL_CHOICE_NAME_)}; \
  constexpr std::span<const char* const> luxel_choice_names(E) {                       \
    return kChoiceNamesOf##E;                                                          \
  }

// Inside a class (SkySettings::Kind): the same, the names a static member
// and their function a friend, which argument-dependent lookup finds too.
#define LUXEL_MEMBER_CHOICE_ENUM(E, LIST)                                              \
  enum class E { LIST(LUXEL_CHOICE_ENUMERATOR_) };                                     \
  static constexpr const char* const kChoiceNamesOf##E[] = {LIST(LUXEL_CHOICE_NAME_)}; \
  friend constexpr std::span<const char* const> luxel_choice_names(E) {                \
    return kChoiceNamesOf##E;                                                          \
  }

namespace luxel {

// Every name of E, in list order.
template <class E>
constexpr std::span<const char* const> choice_names() {
  return luxel_choice_names(E{});
}

template <class E>
constexpr const char* choice_name(E value) {
  const auto names = luxel_choice_names(value);
  const auto i = static_cast<size_t>(value);
  return i < names.size() ? names[i] : "?";
}

template <class E>
std::optional<E> parse_choice(std::string_view name) {
  const auto names = choice_names<E>();
  for (size_t i = 0; i < names.size(); ++i)
    if (name == names[i]) return static_cast<E>(i);
  return std::nullopt;
}

// The names as a settings schema's Setting::choices takes them.
template <class E>
std::vector<const char*> choice_list() {
  const auto names = choice_names<E>();
  return {names.begin(), names.end()};
}

}  // namespace luxel
