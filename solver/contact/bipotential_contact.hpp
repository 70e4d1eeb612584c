// The semi-explicit scheme's contact solve (Cros et al. 2010, Eqs. (4)-(5)): frictional contact
// solved implicitly by the bi-potential method inside an explicit step. After evaluate() gives
// the free accelerations, contact_phase() finds the reactions R at t+dt so that
// U = U_lib + U_c, U_c = dt^2 M^-1 R, leaves no contact node inside an obstacle (position
// level), and adds R/m to the accelerations. The candidates, frames and observables are the
// shared contact module's (contact_set.hpp); this file holds the local problems and their
// Gauss-Seidel solution only.
#pragma once

#include <vector>

#include "solver/contact/contact_set.hpp"

namespace ricochet {

template <int D>
struct BipotentialContactT {
  ContactSetT<D> set;
  // Per candidate, the local problem x = x_free + w r of the step.
  std::vector<typename Space<D>::Local> x_free;
  std::vector<double> weight;            // w = local compliance
  std::vector<VecD<D>, Eigen::aligned_allocator<VecD<D>>> node_reaction;  // per node, sum of r in global axes [N]
  // Frame updates (ContactSettings::frame_updates): node_reaction[j] is current where
  // node_mark[j] == mark; each active contact's reaction in global axes before its frame changes.
  std::vector<unsigned> node_mark;
  unsigned mark = 0;
  std::vector<VecD<D>, Eigen::aligned_allocator<VecD<D>>> reaction_global;
  std::vector<unsigned char> frame_kept;  // 1: the update found no face; the step's frame stays
};
using BipotentialContact = BipotentialContactT<2>;

// The contact set (make_contact_set) with the local problems' arrays allocated.
template <class M>
BipotentialContactT<M::kDim> make_bipotential_contact(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                                            const std::vector<std::vector<double>>& friction,
                                            const std::vector<PrescribedDof>& prescribed,
                                            const std::vector<BodyPair>& pairs = {});

// After evaluate(): solves the contact reactions of step n -> n+1 and adds them to s.a.
// Allocates nothing.
template <class M>
void contact_phase(const M& model, const std::vector<ObstacleOf<M>>& obstacles, const ContactSettings& settings,
                   BipotentialContactT<M::kDim>& c, State& s);

// Adds the reactions of the last contact_phase() (c.reaction of c.active) to s.a as R/m, the
// same operations contact_phase() ends with. The explicit loop calls it on a copy of the free
// accelerations to observe the state at t_n with the reactions that act at t_n (docs/outputs.md,
// History semantics). Allocates nothing.
template <class M>
void add_reaction_accelerations(const M& model, const BipotentialContactT<M::kDim>& c, State& s);

}  // namespace ricochet
