#include <gtest/gtest.h>
#include "input/gcode.hpp"
TEST(Gcode, Placeholder) {}
