#include "fragg_map/field_names.h"

#include <cctype>

namespace fragg {

namespace {
// Characters that continue a field path: a match must not be preceded or followed by one.
bool partOfName(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
}
}  // namespace

std::string renameFields(const std::string& message, const std::vector<FieldName>& names,
                         const std::string& quote) {
  std::string out;
  out.reserve(message.size() + 16);
  size_t i = 0;
  while (i < message.size()) {
    const FieldName* match = nullptr;
    if (i == 0 || !partOfName(message[i - 1])) {
      for (const FieldName& n : names) {
        if (n.field.empty() || message.compare(i, n.field.size(), n.field) != 0) continue;
        const size_t end = i + n.field.size();
        // A sentence may end right after a field: "x must exceed y." keeps its full stop.
        const bool whole =
            end == message.size() || !partOfName(message[end]) ||
            (message[end] == '.' && (end + 1 == message.size() || !partOfName(message[end + 1])));
        if (whole && (!match || n.field.size() > match->field.size())) match = &n;
      }
    }
    if (match) {
      out += quote + match->name + quote;
      i += match->field.size();
    } else {
      out += message[i++];
    }
  }
  return out;
}

}  // namespace fragg
