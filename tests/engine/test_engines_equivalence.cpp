#include <gtest/gtest.h>
TEST(EnginesPlaceholder, Builds) { SUCCEED(); }
