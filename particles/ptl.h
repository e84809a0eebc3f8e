/* ptl.h — the one public header of the particle library (DESIGN.md §5).
 *
 * Two particle models share this library:
 *   - cluster dynamics (cd_*): pair potentials from an EOS cold curve, paper 002;
 *   - the Hamiltonian discrete model (dm_*): least-squares deformation gradient, paper 000;
 * and the symplectic RKN integrators (rkn_*) both use.
 */
#ifndef MSCALE_PTL_H
#define MSCALE_PTL_H

#include "core.h"
#include "eos.h"

/* === Cluster dynamics (cd_) === */

/* === Symplectic RKN integrators (rkn_) === */

/* === Hamiltonian discrete model (dm_) === */

#endif /* MSCALE_PTL_H */
