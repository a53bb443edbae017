// How the tools' process keeps the memory it frees.
#pragma once

namespace defocus {

/// Keeps the memory the process frees in its heap, for its next
/// allocations, rather than handing it back to the kernel. Called first
/// in a tool's main, before any thread starts. Not for the library: a
/// process that loads it (oiiotool, Python) keeps its own policy.
void keep_freed_memory();

}  // namespace defocus
