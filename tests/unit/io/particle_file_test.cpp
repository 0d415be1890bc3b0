// Particle files (io/particle_file.hpp): what a good file gives, and each kind of bad content
// refused with the file and the row named.
#include "libpd/io/particle_file.hpp"

#include <gtest/gtest.h>
#include <string>

namespace {

/// The message of the ParticleFileError `text` raises, or "" if it parses.
std::string error_of(const std::string& text, int dim = 2) {
  try {
    pd::parse_particle_csv(text, "p.csv", dim);
  } catch (const pd::ParticleFileError& e) {
    return e.what();
  }
  return "";
}

TEST(ParticleFile, ReadsPositionsVolumesAndSizesInAnyColumnOrder) {
  const pd::PointCloud c = pd::parse_particle_csv("# graded plate\n"
                                                  "volume, y, x, h, note\n"
                                                  "1e-4, 0.5, 0.25, 0.01, a\n"
                                                  "\n"
                                                  "4e-4, 0.5, 0.75, 0.02, b\n",
                                                  "p.csv", 2);
  ASSERT_EQ(c.count(), 2U);
  EXPECT_EQ(c.position[1][0], 0.75);
  EXPECT_EQ(c.position[1][1], 0.5);
  EXPECT_EQ(c.volume[1], 4e-4);
  ASSERT_EQ(c.size.size(), 2U);
  EXPECT_EQ(c.size[0], 0.01);
  // Mass and density instead of volume; no h: sizes are derived later (eq. 115).
  const pd::PointCloud m =
      pd::parse_particle_csv("x,y,z,mass,density\n0,0,0,7.8,7800\n", "p.csv", 3);
  EXPECT_DOUBLE_EQ(m.volume[0], 1e-3);
  EXPECT_TRUE(m.size.empty());
}

TEST(ParticleFile, MissingColumnIsRefusedAtTheHeader) {
  EXPECT_EQ(error_of("# comment\nx,volume\n0,1\n"),
            "p.csv:2: the header has no column 'y' (a 2D body needs x, y)");
  EXPECT_EQ(error_of("x,y,z,volume\n0,0,0,1\n", 2), ""); // z is not read in 2D
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n", 3),
            "p.csv:1: the header has no column 'z' (a 3D body needs x, y, z)");
  EXPECT_EQ(error_of("x,y,mass\n0,0,1\n"),
            "p.csv:1: the header has no column 'volume' (or both 'mass' and 'density')");
  EXPECT_EQ(error_of("x,y,volume\n0,0.5\n"), "p.csv:2: no value in column 'volume'");
}

TEST(ParticleFile, NonFiniteOrNonNumericValueIsRefusedWithItsRow) {
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,nan,1\n"), "p.csv:3: 'nan' in column 'y' is not finite");
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,inf\n"),
            "p.csv:3: 'inf' in column 'volume' is not finite");
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,1e999\n"),
            "p.csv:3: '1e999' in column 'volume' is not a number");
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,abc,1\n"),
            "p.csv:3: 'abc' in column 'y' is not a number");
}

TEST(ParticleFile, NegativeOrZeroVolumeAndSizeAreRefused) {
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,-2e-4\n"), "p.csv:3: volume -0.0002 is not positive");
  EXPECT_EQ(error_of("x,y,volume\n0,0,0\n"), "p.csv:2: volume 0 is not positive");
  EXPECT_EQ(error_of("x,y,mass,density\n0,0,1,-5\n"), "p.csv:2: density -5 is not positive");
  EXPECT_EQ(error_of("x,y,volume,h\n0,0,1,-0.1\n"), "p.csv:2: size h -0.1 is not positive");
}

TEST(ParticleFile, DuplicatePointIsRefusedNamingBothRows) {
  EXPECT_EQ(error_of("x,y,volume\n0,0,1\n1,0,1\n# again\n0,0,2\n"),
            "p.csv:5: duplicate point (0, 0, 0): row 2 has the same position");
}

TEST(ParticleFile, EmptyFilesAndUnreadablePathsAreRefused) {
  EXPECT_EQ(error_of("# nothing\n"), "p.csv: no header row (x, y[, z], volume …)");
  EXPECT_EQ(error_of("x,y,volume\n"), "p.csv: no particle rows after the header");
  EXPECT_THROW(pd::read_particle_csv("/nonexistent/p.csv", 2), pd::ParticleFileError);
}

} // namespace
