#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

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

TEST(TaskFile, CsvStepsColumnMakesAMultiStopTask) {
  auto t = csvToTasks("id,steps\nm1,pick:P-1:L-42:2;drop:D-2:L-42;wait:::5;goto:X;charge:C-1\n", "m.csv");
  ASSERT_TRUE(t) << t.error().message;
  ASSERT_EQ(t->size(), 1u);
  const auto& steps = (*t)[0]["steps"];
  ASSERT_EQ(steps.size(), 5u);
  EXPECT_EQ(
      steps[0],
      (nlohmann::json{
          {"action", "pick"}, {"station", "P-1"}, {"load_id", "L-42"}, {"duration_ns", 2'000'000'000LL}}));
  EXPECT_EQ(steps[2], (nlohmann::json{{"action", "wait"}, {"duration_ns", 5'000'000'000LL}}));
  EXPECT_EQ(steps[4], (nlohmann::json{{"action", "charge"}, {"station", "C-1"}}));
  auto bad = csvToTasks("id,steps\nm1,goto:X;:Y\nm2,wait:::soon\n", "b.csv");
  ASSERT_FALSE(bad);
  EXPECT_THAT(bad.error().message,
              HasSubstr("b.csv:2: column steps: step 2 \":Y\": expected action:station"));
  EXPECT_THAT(bad.error().message,
              HasSubstr("b.csv:3: column steps: step 1: expected seconds >= 0, got \"soon\""));
}

TEST(TaskFile, JsonShapes) {
  const auto dir = std::filesystem::temp_directory_path();
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream((dir / name).string()) << text;
    return (dir / name).string();
  };
  const auto one = loadTaskFile(write("tf_one.json", R"({"id": "a", "kind": "goto"})"));
  ASSERT_TRUE(one);
  EXPECT_EQ(one->size(), 1u);
  const auto arr = loadTaskFile(write("tf_arr.json", R"([{"id": "a"}, {"id": "b"}])"));
  ASSERT_TRUE(arr);
  EXPECT_EQ(arr->size(), 2u);
  const auto wrapped =
      loadTaskFile(write("tf_wrap.json", R"({"tasks": [{"id": "a"}, {"id": "b"}, {"id": "c"}]})"));
  ASSERT_TRUE(wrapped);
  EXPECT_EQ(wrapped->size(), 3u);
  const auto bad = loadTaskFile(write("tf_bad.json", "[1, 2"));
  ASSERT_FALSE(bad);
  EXPECT_THAT(bad.error().message, HasSubstr("not valid JSON"));
  EXPECT_FALSE(loadTaskFile(write("tf_num.json", "42")));
  EXPECT_FALSE(loadTaskFile("/nonexistent.json"));
}

TEST(TaskFile, CsvSavedByExcelWithAByteOrderMarkIsRead) {
  auto t = csvToTasks("\xEF\xBB\xBFid,kind,pickup,dropoff\r\nt1,transport,P-1,D-1\r\n", "excel.csv");
  ASSERT_TRUE(t) << t.error().message;
  ASSERT_EQ(t->size(), 1u);
  EXPECT_EQ((*t)[0]["id"], "t1");
  const auto dir = std::filesystem::temp_directory_path() / ("fleetctl-bom-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "tasks.json") << "\xEF\xBB\xBF[{\"id\": \"t2\"}]";
  auto j = loadTaskFile((dir / "tasks.json").string());
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(j) << j.error().message;
  EXPECT_EQ((*j)[0]["id"], "t2");
  // Only a leading mark is dropped.
  EXPECT_EQ(withoutBom("a\xEF\xBB\xBF"), "a\xEF\xBB\xBF");
}
