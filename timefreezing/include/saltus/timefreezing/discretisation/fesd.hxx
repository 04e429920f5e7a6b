// Every definition of FesdMpcc (fesd.hpp), assembled from its pieces: the layout and names, the
// stage rows, the complementarity pairs, the step equilibration and the objective, the Jacobian,
// the Hessian, the initial points and the reading of points. Included by the translation unit that
// instantiates FesdMpcc for a scene and an OCP (saltus/timefreezing/instantiate.hxx).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/discretisation/fesd_complementarity.hxx>
#include <saltus/timefreezing/discretisation/fesd_hessian.hxx>
#include <saltus/timefreezing/discretisation/fesd_initial_point.hxx>
#include <saltus/timefreezing/discretisation/fesd_jacobian.hxx>
#include <saltus/timefreezing/discretisation/fesd_layout.hxx>
#include <saltus/timefreezing/discretisation/fesd_objective.hxx>
#include <saltus/timefreezing/discretisation/fesd_points.hxx>
#include <saltus/timefreezing/discretisation/fesd_stage_rows.hxx>
#include <saltus/timefreezing/discretisation/fesd_step_equilibration.hxx>
