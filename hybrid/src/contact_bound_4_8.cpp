// The contact numerics of the contact bounds 4 and 8 (contact_bound) that factorise 3 B x 3 B
// matrices: CoulombSolver<B> (with the polyhedral LCP of its restarts) and MinNormSolver<3 B>,
// compiled once here. Both hold a CompleteOrthogonalDecomposition of the same matrix type,
// whose code (most of the compile time) is then generated once for the two. The bounds are
// split over several files so that parallel builds share them out.
#include <saltus/hybrid/contact/coulomb_solver.hxx>
#include <saltus/hybrid/contact/linear_solve.hxx>

namespace saltus {

template class MinNormSolver<12>;
template class MinNormSolver<24>;
template class detail::PolyhedralContactLcp<4, detail::coulomb_restart_sides(4)>;
template class detail::PolyhedralContactLcp<8, detail::coulomb_restart_sides(8)>;
template class CoulombSolver<4>;
template class CoulombSolver<8>;

}  // namespace saltus
