#include "acquisition/json_text.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

namespace gf {
namespace {

// A folder named in Latin-1 ("caf\xe9") is not UTF-8: nlohmann's dump() throws on it, JsonText
// writes U+FFFD instead and the text reads back.
TEST(JsonText, WritesPathsThatAreNotUtf8) {
  const std::string path = "/data/caf\xe9/run";
  nlohmann::ordered_json j;
  j["input"] = {{"path", path}};
  EXPECT_THROW(j.dump(2), nlohmann::json::type_error);
  const std::string text = JsonText(j);
  EXPECT_NE(text.find("/data/caf\xef\xbf\xbd/run"), std::string::npos) << text;
  EXPECT_EQ(nlohmann::json::parse(text)["input"]["path"], "/data/caf\xef\xbf\xbd/run");
  const nlohmann::json plain = {{"path", "/data/caf\xc3\xa9"}};  // valid UTF-8 stays as it is
  EXPECT_EQ(JsonText(plain, -1), "{\"path\":\"/data/caf\xc3\xa9\"}");
}

}  // namespace
}  // namespace gf
