// Lemke's method and the planar contact solver, compiled once here for the bounds declared
// extern in lemke.hpp (contact bounds 1, 2, 4, 8, 16, 32 and the LCP sizes they use).
#include <saltus/hybrid/contact/lemke.hxx>

namespace saltus {

template class detail::LemkeLcp<4>;
template class detail::LemkeLcp<8>;
template class detail::LemkeLcp<14>;
template class detail::LemkeLcp<16>;
template class detail::LemkeLcp<28>;
template class detail::LemkeLcp<32>;
template class detail::LemkeLcp<56>;
template class detail::LemkeLcp<64>;
template class detail::LemkeLcp<96>;
template class detail::LemkeLcp<128>;
template class detail::PolyhedralContactLcp<1, 2>;
template class detail::PolyhedralContactLcp<2, 2>;
template class detail::PolyhedralContactLcp<4, 2>;
template class detail::PolyhedralContactLcp<8, 2>;
template class detail::PolyhedralContactLcp<16, 2>;
template class detail::PolyhedralContactLcp<32, 2>;
template class LemkeSolver<1>;
template class LemkeSolver<2>;
template class LemkeSolver<4>;
template class LemkeSolver<8>;
template class LemkeSolver<16>;
template class LemkeSolver<32>;

}  // namespace saltus
