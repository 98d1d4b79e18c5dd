// squeeze::meshing (private) — running a call that may die of SIGFPE, and surviving it.
#pragma once
#include <functional>

namespace squeeze::meshing::detail {

/// Runs f() on this thread; where f raises SIGFPE on this thread, returns false instead of the
/// process dying. It is for CGAL 5.5's sliver exuder (Mesh_3 Slivers_exuder::pump_vertex): beside
/// a numerically flat cell it computes a NaN or infinite weight and compares it exactly, and GMP
/// (mpq_set_d) answers a NaN or infinity with raise(SIGFPE) — `squeeze mesh` of a 64-sided cone at
/// 300 tetrahedra died with exit 136. The exuder changes the triangulation only after that
/// comparison, one vertex at a time, so what it had done before stays consistent; what it would
/// have freed on its way out is leaked (a few containers, once per such input). SIGFPE raised
/// anywhere else, or on another thread, does what it did before. Other signals are untouched.
/// Source: squeeze's own (POSIX sigaction, sigsetjmp/siglongjmp).
bool run_unless_sigfpe(const std::function<void()>& f);

}  // namespace squeeze::meshing::detail
