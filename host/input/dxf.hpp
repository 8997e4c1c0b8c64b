// SPDX-License-Identifier: Apache-2.0
// DXF reader (through dxflib): the drawing's curves as a toolpath (3 axes, millimetres).
//
// Entities of the ENTITIES section: LINE, ARC, CIRCLE, ELLIPSE, LWPOLYLINE and POLYLINE/VERTEX (2-D
// with bulges, bulge = tan(included angle / 4), positive counter-clockwise; closed flag; 3-D
// polylines), SPLINE (degree, knots, control points, weights: a B-spline or NURBS as given; splines
// with fit points only are refused). Arcs and circles become exact rational quadratic NURBS. Planar
// entities are given in their object coordinate system (extrusion direction, DXF's arbitrary axis
// algorithm) and mapped to world coordinates; 3-D coordinates are kept.
// Units: $INSUNITS inches, feet, mm, cm, m; unitless or missing: millimetres, with a note.
//
// Cuts: entities whose end points meet within 1e-6 mm are chained into one cut (an entity is run
// backwards where that joins it; the joint is closed exactly), in the order of each chain's first
// entity in the file; the rest are each a cut of their own. Cuts are joined by rapids, the first from
// the origin (input/cuts.hpp).
// Entities inside BLOCK definitions are drawn by the INSERTs of the block (base point, scale,
// rotation, insertion point, column/row array; blocks inserted in blocks), each named
// "<file>: entity <n> (INSERT) of block <name>, its <TYPE>"; TEXT, HATCH, DIMENSION, POINT and
// others are skipped with a note.
// Errors: InputError "<file>: entity <n> (<TYPE>): <why>" (n counts the entities of the ENTITIES
// section from 1), "<file>: cannot open", "<file>: no curves".
#pragma once
#include <string>

#include "input/toolpath.hpp"

namespace traj::input {

Toolpath read_dxf(const std::string& file);

}  // namespace traj::input
