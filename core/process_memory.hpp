#pragma once
// This process's memory as the kernel accounts it (Linux /proc/self/status), for benchmarks and
// soak runs that must show memory stays bounded.

namespace lasercell {

/// Resident set size now, MB (VmRSS); 0 when /proc is not readable.
double ResidentMb();

}  // namespace lasercell
