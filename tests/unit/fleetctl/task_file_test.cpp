#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "task_file.hpp"

using namespace fleet::ctl;
using ::testing::HasSubstr;

TEST(TaskFile, CsvToTasks) {
  auto t = csvToTasks(
      "id,kind,pickup,dropoff,priority,load_s\n"
      "# a comment\n"
      "t1,transport,P-1,D-1,3,2.5\n"
      "\"t,2\",goto,,,,\n",
      "x.csv");
  ASSERT_TRUE(t) << t.error().message;
  ASSERT_EQ(t->size(), 2u);
  EXPECT_EQ((*t)[0]["priority"], 3);
  EXPECT_EQ((*t)[0]["load_duration_ns"], 2'500'000'000LL);
  EXPECT_EQ((*t)[1]["id"], "t,2");
  EXPECT_FALSE((*t)[1].contains("pickup"));
}

TEST(TaskFile, CsvErrorsNameLineAndColumn) {
  auto t = csvToTasks("id,kind,colour\nt1,goto,red\nt2,goto\nt3,goto,x\n", "bad.csv");
  ASSERT_FALSE(t);
  EXPECT_THAT(t.error().message, HasSubstr("bad.csv:1: unknown column \"colour\""));
  EXPECT_THAT(t.error().message, HasSubstr("bad.csv:3: 2 fields, the header has 3"));
  auto u = csvToTasks("id,priority,load_s\nt1,high,1\nt2,1,-3\n", "u.csv");
  ASSERT_FALSE(u);
  EXPECT_THAT(u.error().message, HasSubstr("u.csv:2: column priority: expected an integer, got \"high\""));
  EXPECT_THAT(u.error().message, HasSubstr("u.csv:3: column load_s: expected seconds >= 0, got \"-3\""));
  EXPECT_FALSE(csvToTasks("kind\ngoto\n", "n.csv"));
}

TEST(TaskFile, JsonShapes) {
  EXPECT_FALSE(loadTaskFile("/nonexistent.json"));
}
