#include "../engine/test.h"
Test(rocks, placeholder) {}
