#include <gtest/gtest.h>
TEST(Placeholder, test_render) { SUCCEED(); }
