// SPDX-License-Identifier: Apache-2.0
// The rsu-vehicle CLI's NDT pose CSV: what parses, and that every error names its line.
#include "vehicle_client/ndt_csv.h"

#include <gtest/gtest.h>

#include <string>

namespace rsu::vehicle_client {
namespace {

// The line number an error names, or 0 when the line parsed.
std::size_t error_line(NdtCsvParser& parser, const std::string& line) {
  try {
    parser.parse_line(line);
  } catch (const NdtCsvError& e) {
    EXPECT_NE(std::string(e.what()).find("line " + std::to_string(e.line())), std::string::npos) << e.what();
    return e.line();
  }
  return 0;
}

TEST(NdtCsv, ShortRowsParseAfterTheHeader) {
  NdtCsvParser parser;
  EXPECT_FALSE(parser.parse_line("# recorded on route 7").has_value());
  EXPECT_FALSE(parser.parse_line("time_ns,x,y,yaw").has_value());
  EXPECT_TRUE(parser.has_header());
  EXPECT_FALSE(parser.has_variances());
  EXPECT_FALSE(parser.parse_line("").has_value());
  const auto row = parser.parse_line("1700000000123456789, 12.5,-3.25 ,1.5e-1\r");
  ASSERT_TRUE(row.has_value());
  EXPECT_EQ(row->time, 1700000000123456789LL);
  EXPECT_DOUBLE_EQ(row->pose.x, 12.5);
  EXPECT_DOUBLE_EQ(row->pose.y, -3.25);
  EXPECT_DOUBLE_EQ(row->pose.yaw, 0.15);
  EXPECT_FALSE(row->variances.has_value());
  EXPECT_EQ(parser.line_number(), 4U);
}

TEST(NdtCsv, LongRowsCarryVariances) {
  NdtCsvParser parser;
  parser.parse_line("time_ns,x,y,yaw,sxx,syy,syaw");
  EXPECT_TRUE(parser.has_variances());
  const auto row = parser.parse_line("5,1,2,3,0.04,0.09,0.0004");
  ASSERT_TRUE(row && row->variances);
  EXPECT_DOUBLE_EQ(row->variances->x(), 0.04);
  EXPECT_DOUBLE_EQ(row->variances->y(), 0.09);
  EXPECT_DOUBLE_EQ(row->variances->z(), 0.0004);
}

TEST(NdtCsv, ErrorsNameTheLine) {
  {
    NdtCsvParser parser;
    EXPECT_EQ(error_line(parser, "1,2,3,4"), 1U);  // no header
  }
  NdtCsvParser parser;
  ASSERT_EQ(error_line(parser, "time_ns,x,y,yaw,sxx,syy,syaw"), 0U);
  ASSERT_EQ(error_line(parser, "1,2,3,4,1,1,1"), 0U);
  EXPECT_EQ(error_line(parser, "1,2,3,4"), 3U);                            // too few fields
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,1,1,9"), 4U);                    // too many
  EXPECT_EQ(error_line(parser, "1.5,2,3,4,1,1,1"), 5U);                    // time not an integer
  EXPECT_EQ(error_line(parser, "1,abc,3,4,1,1,1"), 6U);                    // not a number
  EXPECT_EQ(error_line(parser, "1,2,nan,4,1,1,1"), 7U);                    // not finite
  EXPECT_EQ(error_line(parser, "1,2,3,4,0,1,1"), 8U);                      // zero variance
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,-1,1"), 9U);                     // negative variance
  EXPECT_EQ(error_line(parser, "1,2,3,4e,1,1,1"), 10U);                    // trailing junk
  EXPECT_EQ(error_line(parser, "99999999999999999999,2,3,4,1,1,1"), 11U);  // time overflows int64
  EXPECT_EQ(error_line(parser, "1,2,,4,1,1,1"), 12U);                      // empty field
  EXPECT_EQ(error_line(parser, "2,2,3,4,1,1,1"), 0U);                      // and the parser goes on
}

// The match's quality indicator (issue 18): any of converged, iterations, fitness, in any order after
// the pose (and variances); a file without them leaves the quality unknown.
TEST(NdtCsv, QualityColumnsAreReadByName) {
  NdtCsvParser parser;
  parser.parse_line("time_ns,x,y,yaw,fitness,sxx,syy,syaw,converged,iterations");
  EXPECT_TRUE(parser.has_variances());
  const auto row = parser.parse_line("5,1,2,3,0.047,0.04,0.09,0.0004,1,7");
  ASSERT_TRUE(row && row->variances);
  EXPECT_DOUBLE_EQ(row->variances->y(), 0.09);
  ASSERT_TRUE(row->quality.converged && row->quality.iterations && row->quality.fitness_m2);
  EXPECT_TRUE(*row->quality.converged);
  EXPECT_EQ(*row->quality.iterations, 7);
  EXPECT_DOUBLE_EQ(*row->quality.fitness_m2, 0.047);
  EXPECT_EQ(vehicle::assess(row->quality, {}), vehicle::NdtHealth::kHealthy);

  NdtCsvParser degenerate;
  degenerate.parse_line("time_ns,x,y,yaw,fitness,degeneracy");
  const auto sliding = degenerate.parse_line("5,1,2,3,0.04,8.3");  // fits well, held weakly along the road
  ASSERT_TRUE(sliding && sliding->quality.degeneracy);
  EXPECT_DOUBLE_EQ(*sliding->quality.degeneracy, 8.3);
  EXPECT_EQ(vehicle::assess(sliding->quality, {}), vehicle::NdtHealth::kDegraded);
  const auto flat = degenerate.parse_line("6,1,2,3,0.04,inf");  // no curvature at all
  ASSERT_TRUE(flat && flat->quality.degeneracy);
  EXPECT_EQ(vehicle::assess(flat->quality, {}), vehicle::NdtHealth::kDegraded);
  EXPECT_EQ(vehicle::assess(degenerate.parse_line("7,1,2,3,0.04,5.2")->quality, {}),
            vehicle::NdtHealth::kHealthy);
  EXPECT_FALSE(sliding->quality.weak_axis_rad);

  NdtCsvParser with_axis;  // the direction the match slides along (rad, map frame)
  with_axis.parse_line("time_ns,x,y,yaw,weak_axis,degeneracy,converged");
  const auto along_road = with_axis.parse_line("5,1,2,3,-3.1405,8.3,1");
  ASSERT_TRUE(along_road && along_road->quality.weak_axis_rad);
  EXPECT_DOUBLE_EQ(*along_road->quality.weak_axis_rad, -3.1405);
  EXPECT_TRUE(vehicle::too_degenerate(along_road->quality, {}));
  EXPECT_FALSE(vehicle::match_failed(along_road->quality, {}));
  EXPECT_THROW(with_axis.parse_line("6,1,2,3,inf,8.3,1"), NdtCsvError);
  EXPECT_THROW(with_axis.parse_line("6,1,2,3,nan,8.3,1"), NdtCsvError);

  NdtCsvParser only_converged;
  only_converged.parse_line("time_ns,x,y,yaw,converged");
  EXPECT_FALSE(only_converged.has_variances());
  const auto failed = only_converged.parse_line("5,1,2,3,0");
  ASSERT_TRUE(failed && failed->quality.converged);
  EXPECT_FALSE(*failed->quality.converged);
  EXPECT_FALSE(failed->quality.fitness_m2.has_value());
  EXPECT_EQ(vehicle::assess(failed->quality, {}), vehicle::NdtHealth::kDegraded);

  NdtCsvParser plain;
  plain.parse_line("time_ns,x,y,yaw");
  EXPECT_EQ(vehicle::assess(plain.parse_line("5,1,2,3")->quality, {}), vehicle::NdtHealth::kUnknown);
}

TEST(NdtCsv, BadHeadersAndQualityValuesNameTheLine) {
  for (const char* header :
       {"time_ns,x,y", "x,time_ns,y,yaw", "time_ns,x,y,yaw,sxx,syy", "time_ns,x,y,yaw,speed",
        "time_ns,x,y,yaw,fitness,fitness", "time_ns,x,y,yaw,x"}) {
    NdtCsvParser parser;
    EXPECT_EQ(error_line(parser, "# comment"), 0U);
    EXPECT_EQ(error_line(parser, header), 2U) << header;
  }
  NdtCsvParser parser;
  ASSERT_EQ(error_line(parser, "time_ns,x,y,yaw,converged,iterations,fitness"), 0U);
  EXPECT_EQ(error_line(parser, "1,2,3,4,2,5,0.1"), 2U);    // converged neither 0 nor 1
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,-5,0.1"), 3U);   // negative count
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,5.5,0.1"), 4U);  // not a count
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,5,-0.1"), 5U);   // negative fitness
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,5,inf"), 6U);    // not finite
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,5"), 7U);        // a field missing
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,5,nan"), 8U);    // NaN
  EXPECT_EQ(error_line(parser, "1,2,3,4,1,30,0.1"), 0U);   // and the parser goes on
  NdtCsvParser d;
  ASSERT_EQ(error_line(d, "time_ns,x,y,yaw,degeneracy"), 0U);
  EXPECT_EQ(error_line(d, "1,2,3,4,0.5"), 2U);  // below 1
  EXPECT_EQ(error_line(d, "1,2,3,4,nan"), 3U);
  EXPECT_EQ(error_line(d, "1,2,inf,4,2"), 4U);  // only a degeneracy may be infinite
}

}  // namespace
}  // namespace rsu::vehicle_client
