// How the tools' process keeps the memory it frees.
#pragma once

namespace defocus {

/// Keeps the memory the process frees in its heap, for its next
/// allocations, rather than handing it back to the kernel. Called in a
/// tool's main before any thread of ours allocates (a thread that has
/// allocated keeps an arena of its own; the threads that libraries start
/// before main have not). Not for a run that writes a deep result:
/// its sample lists, of every size, fragment the one heap (the 4K example
/// written deep peaked at 2.3 GB against 1.6 GB). Not for the library
/// either: a process that loads it (oiiotool, Python) keeps its own
/// policy.
void keep_freed_memory();

/// The bytes of memory the process has resident now (its code, libraries
/// and heap), 0 where the system does not say.
double resident_bytes();

}  // namespace defocus
