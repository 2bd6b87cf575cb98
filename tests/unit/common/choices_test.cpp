// common/choices.h: one X-macro list gives an enum its names, parser and
// name list, at namespace scope and inside a class.
#include "common/choices.h"

#include <gtest/gtest.h>

namespace luxel {
namespace {

#define TEST_FRUIT_CHOICES(X) \
  X(kApple, "apple") X(kBloodOrange, "blood-orange") X(kCherry, "cherry")
LUXEL_CHOICE_ENUM(Fruit, TEST_FRUIT_CHOICES)

struct Basket {
#define TEST_SIZE_CHOICES(X) X(kSmall, "small") X(kLarge, "large")
  LUXEL_MEMBER_CHOICE_ENUM(Size, TEST_SIZE_CHOICES)
};

TEST(Choices, NamesFollowTheList) {
  EXPECT_STREQ(choice_name(Fruit::kApple), "apple");
  EXPECT_STREQ(choice_name(Fruit::kBloodOrange), "blood-orange");
  EXPECT_STREQ(choice_name(Fruit::kCherry), "cherry");
  EXPECT_STREQ(choice_name(static_cast<Fruit>(7)), "?");  // not a value of the list
  EXPECT_EQ(static_cast<int>(Fruit::kCherry), 2);         // numbered in list order
  EXPECT_EQ(choice_list<Fruit>(),
            (std::vector<const char*>{choice_name(Fruit::kApple), choice_name(Fruit::kBloodOrange),
                                      choice_name(Fruit::kCherry)}));
  static_assert(choice_names<Fruit>().size() == 3);
}

TEST(Choices, ParseIsTheInverseOfName) {
  EXPECT_EQ(parse_choice<Fruit>("blood-orange"), Fruit::kBloodOrange);
  EXPECT_EQ(parse_choice<Fruit>("Apple"), std::nullopt);  // names are exact
  EXPECT_EQ(parse_choice<Fruit>(""), std::nullopt);
}

TEST(Choices, MemberEnumsToo) {
  EXPECT_STREQ(choice_name(Basket::Size::kLarge), "large");
  EXPECT_EQ(parse_choice<Basket::Size>("small"), Basket::Size::kSmall);
  EXPECT_EQ(choice_list<Basket::Size>().size(), 2u);
}

}  // namespace
}  // namespace luxel
