// SPDX-License-Identifier: Apache-2.0
// SVG reader: the drawing's outlines as a toolpath (2 axes, millimetres).
//
// Every <path> and every basic shape (<line>, <polyline>, <polygon>, <rect> with rounded corners,
// <circle>, <ellipse>) is converted to path segments: lines, quadratic and cubic Beziers, elliptical
// arcs as exact rational quadratic NURBS (svg_path.hpp). Each subpath is one cut; consecutive cuts
// are joined by rapids, the first from the origin (input/cuts.hpp).
//
// Coordinates: the element's transform and those of its ancestors (<g>, <a>), then the root's
// viewBox into its viewport (width/height with units mm, cm, in, pt, pc, px, Q or none = px at
// 96 px/in; preserveAspectRatio honoured), giving millimetres in SVG's frame (y down from the top
// edge). The y axis is then flipped about the page: y_mm = page height - y, so that the origin is
// the page's bottom-left corner, y points up and the drawing appears as it does on screen. Without
// a known page height (no height, no viewBox) the flip is y_mm = -y (origin at the top-left corner).
//
// Skipped without a word: <defs>, <symbol>, <clipPath>, <mask>, <marker>, <pattern>, gradients,
// <style>, <title>, <desc>, <metadata> and elements of other namespaces (sodipodi:, inkscape:).
// Skipped with a note (Toolpath::notes): elements with display:none (hidden layers), <text>,
// <image> and other elements the reader does not draw; a percentage width/height of the root.
// Percentages in shape attributes refer to the root viewport (viewBox, else width/height).
// Errors (InputError "<file>: <element>: <why>", the element named by its id or as "path #3", the
// third shape in document order): unreadable XML, malformed path data (with the character offset),
// unknown units, nested <svg>, a <use> that cannot be followed (another file, an unknown id, a
// cycle, a <symbol> with its own viewBox or size), a file without any shape. A <use> of #id draws
// that element again (from <defs> too) under the use's transform and x, y.
#pragma once
#include <string>

#include "input/toolpath.hpp"

namespace traj::input {

Toolpath read_svg(const std::string& file);
// The same from the text of an SVG document; `name` stands for the file in messages.
Toolpath parse_svg(const std::string& text, const std::string& name);

}  // namespace traj::input
