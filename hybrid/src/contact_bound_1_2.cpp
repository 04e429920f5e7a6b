// The contact numerics of the contact bounds 1 and 2 (contact_bound) that factorise 3 B x 3 B
// matrices: CoulombSolver<B> (with the polyhedral LCP of its restarts) and MinNormSolver<3 B>,
// compiled once here. Both hold a CompleteOrthogonalDecomposition of the same matrix type,
// whose code (most of the compile time) is then generated once for the two. The bounds are
// split over several files so that parallel builds share them out.
#include <saltus/hybrid/contact/coulomb_solver.hxx>
#include <saltus/hybrid/contact/linear_solve.hxx>

namespace saltus {

template class MinNormSolver<3>;
template class MinNormSolver<6>;
template class detail::PolyhedralContactLcp<1, detail::coulomb_restart_sides(1)>;
template class detail::PolyhedralContactLcp<2, detail::coulomb_restart_sides(2)>;
template class CoulombSolver<1>;
template class CoulombSolver<2>;

}  // namespace saltus
