// Room in a caller's kept buffer with headroom (internal).
#pragma once

#include <cstddef>

namespace fragg {

/// Makes room for `n` elements in `*v`, half as many again when it has to grow. For buffers a
/// caller keeps between calls (the changed-block lists): resize() after clear() grows a
/// std::vector to exactly n, so every new largest list copied the buffer into fresh memory and
/// faulted its pages in; with headroom that happens a few times over a run, not at every new
/// maximum.
template <class Vector>
void reserveWithHeadroom(Vector* v, size_t n) {
  if (v->capacity() < n) v->reserve(n + n / 2);
}

}  // namespace fragg
