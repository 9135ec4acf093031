#include "rig/signal/streaming_correlator.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "test_data.hpp"

namespace rig::signal {
namespace {

using test::white;

struct Record {
  Eigen::VectorXd u, y;
};

Record record(Eigen::Index n, std::uint64_t seed) {
  Record r;
  r.u = white(n, seed);
  r.y = test::fir(Eigen::Vector3d(0.2, 1.0, -0.4), r.u) + 0.3 * white(n, seed + 1);
  return r;
}

// Pushes the record in the given (uneven) block sizes, the last block taking the rest.
void push_in_blocks(StreamingCorrelator& sc, const Record& rec,
                    const std::vector<Eigen::Index>& sizes) {
  Eigen::Index at = 0;
  for (Eigen::Index s : sizes) {
    sc.push(rec.u.segment(at, s), rec.y.segment(at, s));
    at += s;
  }
  sc.push(rec.u.tail(rec.u.size() - at), rec.y.tail(rec.u.size() - at));
}

double max_abs_diff(const Correlation& a, const Correlation& b) {
  EXPECT_EQ(a.zero_index, b.zero_index);
  EXPECT_EQ(a.size(), b.size());
  return (a.r - b.r).cwiseAbs().maxCoeff();
}

TEST(StreamingCorrelator, CumulativeBlocksEqualBatchForEveryKind) {
  const Record rec = record(6000, 101);
  for (auto kind : {CorrelatorKind::kDirect, CorrelatorKind::kFft, CorrelatorKind::kRelay,
                    CorrelatorKind::kPolarity}) {
    for (int skip : {1, 3, 8}) {
      for (Eigen::Index z : {Eigen::Index{-1}, Eigen::Index{0}, Eigen::Index{63}}) {
        const CorrelatorOptions co{.lags = 64, .zero_index = z, .skip = skip, .kind = kind};
        StreamingCorrelator sc(
            {.correlator = co, .averaging = Averaging::kCumulative, .block_samples = 500});
        push_in_blocks(sc, rec, {1, 7, 30, 300, 1000, 63, 64, 65});
        const std::string what = std::string(to_string(kind)) + " skip " + std::to_string(skip) +
                                 " z " + std::to_string(z);
        EXPECT_LT(max_abs_diff(sc.ryu(), cross_correlation(rec.y, rec.u, co)), 1e-12) << what;
        EXPECT_LT(max_abs_diff(sc.ruu(), auto_correlation(rec.u, co)), 1e-12) << what;
        EXPECT_EQ(sc.products(), products_per_lag(co, rec.u.size())) << what;
        EXPECT_EQ(sc.blocks(), 12) << what;  // 6000 / 500
      }
    }
  }
}

TEST(StreamingCorrelator, SampleBySampleEqualsBatch) {
  const Record rec = record(3000, 111);
  const CorrelatorOptions co{.lags = 256, .skip = 2, .kind = CorrelatorKind::kRelay};
  StreamingCorrelator sc({.correlator = co, .averaging = Averaging::kCumulative});
  for (Eigen::Index i = 0; i < rec.u.size(); ++i) {
    sc.push(rec.u[i], rec.y[i]);
    const Eigen::Index n = i + 1;
    if (n == 256 || n == 257 || n == 1001 || n == 2999) {  // reads mid-stream see every product
      const Eigen::VectorXd u = rec.u.head(n), y = rec.y.head(n);
      EXPECT_LT(max_abs_diff(sc.ryu(), cross_correlation(y, u, co)), 1e-12) << n;
      EXPECT_LT(max_abs_diff(sc.ruu(), auto_correlation(u, co)), 1e-12) << n;
      EXPECT_EQ(sc.products(), products_per_lag(co, n)) << n;
    }
  }
  EXPECT_LT(max_abs_diff(sc.ryu(), cross_correlation(rec.y, rec.u, co)), 1e-12);
  EXPECT_EQ(sc.samples(), 3000);
}

// The exponential average, replayed by hand: block b holds the anchors t whose last needed
// sample t + z arrived during block b; R_1 = mean_1, R_b = R_{b-1} + (mean_b - R_{b-1}) / W.
TEST(StreamingCorrelator, ExponentialAverageFollowsTheRecursion) {
  const Record rec = record(5000, 121);
  const Eigen::Index lags = 40, z = 10, p = lags - 1 - z, block = 700;
  const double w = 10.0;
  const CorrelatorOptions co{.lags = lags, .zero_index = z, .skip = 4};
  StreamingCorrelator sc({.correlator = co, .weight = w, .block_samples = block});
  push_in_blocks(sc, rec, {333, 1200, 17});

  Eigen::VectorXd avg(lags);
  int blocks = 0;
  Eigen::Index anchor = p;
  for (Eigen::Index end = block; end <= rec.u.size(); end += block) {
    Eigen::Index last = anchor;
    while (last + 4 + z <= end - 1) last += 4;  // last anchor completed in this block
    Eigen::VectorXd mean(lags);
    for (Eigen::Index i = 0; i < lags; ++i)
      mean[i] = test::naive_lag(rec.y, rec.u, i - z, anchor, last, 4);
    avg = blocks == 0 ? mean : Eigen::VectorXd(avg + (mean - avg) / w);
    ++blocks;
    anchor = last + 4;
  }
  EXPECT_EQ(sc.blocks(), blocks);
  EXPECT_LT((sc.ryu().r - avg).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(StreamingCorrelator, EachPushIsABlockWhenBlockSamplesIsZero) {
  const Record rec = record(2000, 131);
  const CorrelatorOptions co{.lags = 32};
  StreamingCorrelator sc({.correlator = co, .weight = 1.0, .block_samples = 0});
  sc.push(rec.u.head(1000), rec.y.head(1000));
  sc.push(rec.u.tail(1000), rec.y.tail(1000));
  EXPECT_EQ(sc.blocks(), 2);
  // W = 1 keeps only the last block: the anchors completed by the second push.
  const Eigen::Index z = sc.ryu().zero_index, p = 31 - z;
  const Eigen::Index first = 1000 - z;  // first anchor whose window ends at sample 1000
  for (Eigen::Index i = 0; i < 32; ++i) {
    EXPECT_NEAR(sc.ryu().r[i], test::naive_lag(rec.y, rec.u, i - z, first, 1999 - z, 1), 1e-12);
  }
  EXPECT_GE(first, p);
}

TEST(StreamingCorrelator, ResetStartsAfreshAndEmptyStateIsReported) {
  const Record rec = record(500, 141);
  StreamingCorrelator sc({.correlator = {.lags = 64}, .averaging = Averaging::kCumulative});
  EXPECT_THROW((void)sc.ruu(), std::logic_error);
  sc.push(rec.u.head(63), rec.y.head(63));
  EXPECT_EQ(sc.products(), 0);
  EXPECT_THROW((void)sc.ryu(), std::logic_error);
  sc.push(rec.u.tail(437), rec.y.tail(437));
  const Correlation before = sc.ryu();
  sc.reset();
  EXPECT_EQ(sc.samples(), 0);
  EXPECT_EQ(sc.products(), 0);
  sc.push(rec.u, rec.y);
  EXPECT_LT(max_abs_diff(sc.ryu(), before), 1e-15);
}

TEST(StreamingCorrelator, BadArgumentsNameTheProblem) {
  using ::testing::HasSubstr;
  auto message = [](const StreamingOptions& o) -> std::string {
    try {
      StreamingCorrelator sc(o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_THAT(message({.weight = 0.5}), HasSubstr("weight W must be >= 1"));
  EXPECT_THAT(message({.correlator = {.skip = 0}}), HasSubstr("skip must be >= 1"));
  EXPECT_THAT(message({.block_samples = -1}), HasSubstr("block_samples"));
  StreamingCorrelator sc({});
  EXPECT_THROW(sc.push(Eigen::VectorXd::Ones(3), Eigen::VectorXd::Ones(4)), std::invalid_argument);
}

}  // namespace
}  // namespace rig::signal
