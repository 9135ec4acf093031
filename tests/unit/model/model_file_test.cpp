#include "rig/model/model_file.hpp"

#include <gtest/gtest.h>

#include "../io/test_files.hpp"
#include "rig/model/input_error.hpp"

namespace rig::model {
namespace {

using nlohmann::json;

TEST(ModelFile, RoundTripKeepsEveryField) {
  const auto dir = io::testing::scratch_dir();
  ModelFile m;
  m.tf.num = Eigen::VectorXd::Constant(1, 1.0);
  m.tf.den = (Eigen::VectorXd(3) << 0.07, 0.19, 11.05).finished();
  m.tf.delay_s = 0.12;
  m.cov = Eigen::MatrixXd::Identity(3, 3) * 1e-4;
  m.fit_percent = 91.5;
  m.input = "u";
  m.output = "y";
  m.units = json{{"input", "%"}, {"output", "kW"}};
  m.extra["method"] = "mmfm";
  write_model(dir / "model.json", m);
  const ModelFile r = read_model(dir / "model.json");
  EXPECT_EQ(r.tf.num, m.tf.num);
  EXPECT_EQ(r.tf.den, m.tf.den);
  EXPECT_DOUBLE_EQ(r.tf.delay_s, 0.12);
  ASSERT_TRUE(r.cov.has_value());
  EXPECT_EQ(*r.cov, *m.cov);
  EXPECT_DOUBLE_EQ(*r.fit_percent, 91.5);
  EXPECT_EQ(r.input, "u");
  EXPECT_EQ(r.output, "y");
  EXPECT_EQ(r.units, m.units);
  EXPECT_EQ(r.extra.at("method"), "mmfm");
}

TEST(ModelFile, MinimalDocumentDefaultsDelayToZero) {
  const ModelFile m = model_from_json(json::parse(R"({"type":"tf","num":[2],"den":[1,3]})"), "m");
  EXPECT_DOUBLE_EQ(m.tf.delay_s, 0.0);
  EXPECT_FALSE(m.cov.has_value());
}

void expect_rejected(const std::string& doc, const std::string& words) {
  try {
    model_from_json(json::parse(doc), "model.json");
    FAIL() << "accepted " << doc;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("model.json", 0), 0u) << e.what();
  }
}

TEST(ModelFile, ValidationRejectsBadModels) {
  expect_rejected(R"({"type":"ss","num":[1],"den":[1,1]})", "\"type\"");
  expect_rejected(R"({"type":"tf","num":[1],"den":[]})", "\"den\"");
  expect_rejected(R"({"type":"tf","num":[1]})", "missing key \"den\"");
  expect_rejected(R"({"type":"tf","num":[1,2,3],"den":[1,1]})", "improper");
  expect_rejected(R"({"type":"tf","num":[1],"den":[0,1,1]})", "leading");
  expect_rejected(R"({"type":"tf","num":[1],"den":[1,"x"]})", "finite number");
  expect_rejected(R"({"type":"tf","num":[1],"den":[1,1],"delay_s":-0.1})", "delay_s");
  expect_rejected(R"({"type":"tf","num":[1],"den":[1,1],"cov":[[1,2]]})", "cov");
}

TEST(ModelFile, LeadingZerosInNumeratorDoNotMakeItImproper) {
  const ModelFile m =
      model_from_json(json::parse(R"({"type":"tf","num":[0,0,5],"den":[1,2]})"), "m");
  EXPECT_EQ(m.tf.num.size(), 3);
}

TEST(ModelFile, WritingAnImproperModelThrows) {
  ModelFile m;
  m.tf.num = Eigen::VectorXd::Ones(3);
  m.tf.den = Eigen::VectorXd::Ones(2);
  EXPECT_THROW(model_to_json(m), std::invalid_argument);
}

TEST(ModelFile, UnparsableJsonNamesTheFile) {
  const auto dir = io::testing::scratch_dir();
  io::testing::write_text(dir / "m.json", "{\"type\": \"tf\",");
  EXPECT_THROW(read_model(dir / "m.json"), InputError);
}

}  // namespace
}  // namespace rig::model
