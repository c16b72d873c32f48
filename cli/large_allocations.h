// The program's operator new (large_allocations.cpp): huge pages under large blocks, for the
// commands where that was measured to help.
#pragma once

namespace particlemesh::cli {

/// From now on, ask for transparent huge pages under every block of at least 1 MiB that
/// operator new returns (see large_allocations.cpp for when this helps and when it does not).
void huge_pages_for_large_blocks();

}  // namespace particlemesh::cli
