#pragma once
// One table of names per enum, and the one parser and printer over them. Every enum that is read
// from text (flags, files) or written as text (reports, JSON, messages) declares its table beside
// its declaration:
//
//   enum class Foo { kA, kB };
//   inline constexpr EnumNameEntry<Foo> kFooNames[] = {{Foo::kA, "a"}, {Foo::kB, "b"},
//                                                      {Foo::kB, "bee"}};  // alias
//   constexpr EnumNameTable<Foo> EnumNames(Foo) { return EnumNameTable<Foo>(kFooNames); }
//
// and EnumName(Foo::kB) == "b", ParseEnum("bee", &foo), EnumChoices<Foo>() == "a or b (alias
// bee)". EnumNames is found by argument-dependent lookup, so the table lives in the enum's
// namespace.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace photopose {

// How ParseEnum compares the text with a table's names.
enum class NameMatch {
  kExact,       // byte for byte
  kIgnoreCase,  // ASCII letters compared without case
};

// One spelling of an enum value. The first entry of a value is its name, the one EnumName prints;
// later entries of the same value are aliases that ParseEnum accepts as well.
template <typename Enum>
struct EnumNameEntry {
  Enum value;
  const char* name;
};

// A view of one enum's entries (a static array) and how text is matched against them.
template <typename Enum>
class EnumNameTable {
 public:
  template <std::size_t N>
  constexpr explicit EnumNameTable(const EnumNameEntry<Enum> (&entries)[N],
                                   NameMatch match = NameMatch::kExact)
      : begin_(entries), end_(entries + N), match_(match) {}
  constexpr const EnumNameEntry<Enum>* begin() const { return begin_; }
  constexpr const EnumNameEntry<Enum>* end() const { return end_; }
  constexpr NameMatch match() const { return match_; }

 private:
  const EnumNameEntry<Enum>* begin_;
  const EnumNameEntry<Enum>* end_;
  NameMatch match_;
};

namespace internal {

inline bool SameEnumName(std::string_view text, std::string_view name, NameMatch match) {
  if (text.size() != name.size()) return false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    char a = text[i], b = name[i];
    if (match == NameMatch::kIgnoreCase) {
      if (a >= 'A' && a <= 'Z') a = static_cast<char>(a - 'A' + 'a');
      if (b >= 'A' && b <= 'Z') b = static_cast<char>(b - 'A' + 'a');
    }
    if (a != b) return false;
  }
  return true;
}

// True when `entry` is the first entry of its value (its name, not an alias).
template <typename Enum>
bool IsCanonicalEntry(const EnumNameTable<Enum>& table, const EnumNameEntry<Enum>* entry) {
  for (const EnumNameEntry<Enum>* e = table.begin(); e != entry; ++e)
    if (e->value == entry->value) return false;
  return true;
}

}  // namespace internal

// The name of `value`; "?" for a value outside the table (a cast from a stray integer).
template <typename Enum>
const char* EnumName(Enum value) {
  for (const EnumNameEntry<Enum>& entry : EnumNames(Enum{}))
    if (entry.value == value) return entry.name;
  return "?";
}

// Sets *value to the value named by `text` (its name or an alias, compared as the table says) and
// returns true; returns false and leaves *value unchanged for any other text.
template <typename Enum>
bool ParseEnum(std::string_view text, Enum* value) {
  const EnumNameTable<Enum> table = EnumNames(Enum{});
  for (const EnumNameEntry<Enum>& entry : table) {
    if (internal::SameEnumName(text, entry.name, table.match())) {
      *value = entry.value;
      return true;
    }
  }
  return false;
}

// The same as an expression: ParseEnum<RotationConvention>("opk"); nullopt for any other text.
template <typename Enum>
std::optional<Enum> ParseEnum(std::string_view text) {
  Enum value;
  if (!ParseEnum(text, &value)) return std::nullopt;
  return value;
}

// The accepted names for messages and --help, in table order, each followed by its aliases:
// "rxryrz (alias seed), opk or pok".
template <typename Enum>
std::string EnumChoices() {
  const EnumNameTable<Enum> table = EnumNames(Enum{});
  std::string choices;
  int count = 0, total = 0;
  for (const EnumNameEntry<Enum>* e = table.begin(); e != table.end(); ++e)
    total += internal::IsCanonicalEntry(table, e) ? 1 : 0;
  for (const EnumNameEntry<Enum>* e = table.begin(); e != table.end(); ++e) {
    if (!internal::IsCanonicalEntry(table, e)) continue;
    ++count;
    if (count > 1) choices += count == total ? " or " : ", ";
    choices += e->name;
    std::string aliases;
    int num_aliases = 0;
    for (const EnumNameEntry<Enum>* a = e + 1; a != table.end(); ++a) {
      if (a->value != e->value) continue;
      aliases += (num_aliases++ == 0 ? "" : ", ") + std::string(a->name);
    }
    if (num_aliases > 0) choices += (num_aliases == 1 ? " (alias " : " (aliases ") + aliases + ")";
  }
  return choices;
}

// The names of some values, for messages about a subset of an enum: "none, huber or cauchy".
template <typename Enum, std::size_t N>
std::string EnumNameList(const Enum (&values)[N]) {
  std::string list;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) list += i + 1 == N ? " or " : ", ";
    list += EnumName(values[i]);
  }
  return list;
}

}  // namespace photopose
