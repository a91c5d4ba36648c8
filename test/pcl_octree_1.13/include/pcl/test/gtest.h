#pragma once

// Stands in for PCL's test/include/pcl/test/gtest.h, which PCL does not install.
#include <gtest/gtest.h>
