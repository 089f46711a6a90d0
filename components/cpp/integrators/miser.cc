// miser — recursive stratified sampling (Press & Farrar 1990, "MISER").
//
// Integrate: a node is a sub-box with a budget of N points. A node with
// N < min_points is a leaf: plain Monte Carlo with its N points, giving the
// mean of f over the node and the variance of that mean, s² / N. Any other
// node spends N_e = max(15, ⌊explore_fraction · N⌋) points exploring,
// uniformly in its box, then bisects it along the axis that looks most
// worth stratifying and gives the remaining N − N_e points to its halves:
//
// - Each axis j is cut at a fraction 0.5 ± dither of its length (sign at
//   random per node and axis, so that a symmetric integrand cannot tie
//   every axis); for each half, the spread of f is estimated from the
//   exploration points that fall in it by the range max f − min f (the
//   min/max trick: robust with few points), summed over the outputs, and
//   σ̂ = range^(2/3). The axis chosen minimises σ̂_a + σ̂_b.
// - The halves get N_a = 15 + (N − N_e − 30) · σ̂_a / (σ̂_a + σ̂_b) and
//   N_b = N − N_e − N_a points: the allocation N_a/N ∝ σ_a for plain
//   Monte Carlo in each half, with Press & Farrar's exponent 2/3 on the
//   range for a half that is itself subdivided recursively. Every half
//   gets at least 15 points.
// - The node's mean is p·mean_a + (1−p)·mean_b and its variance
//   p²·var_a + (1−p)²·var_b, p the volume fraction of half a. The
//   exploration points only steer the split and are not in the estimate
//   (they are independent of the points that are, so the estimate stays
//   unbiased); they count in `evaluations`, which is the full budget.
//
// A node that cannot give 15 points to each half after exploring is a leaf
// too. Points are addressed statelessly: the root owns indices 0 … N−1 of
// the sampler's sequence for the job's seed; a node explores with the first
// N_e of its range and hands its halves the next N_a and the last N_b, so a
// result depends only on (seed, budget), not on the order of work. The
// random sign of the cut on axis j of a node is coordinate d + j of its
// first point. The error estimate assumes independent points: use the
// "independent" sampler (a low-discrepancy one still converges).
//
// Batching: the tree is built level by level; the exploration points of
// every interior node and the points of every leaf of a level go to f
// together, in calls of up to 8192 points, rather than one call per node.
//
// Parameters: MiserIntegrator::Parameters() below.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "integration_box.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// Fewest points to explore a node with, and to hand to each half.
constexpr uint64_t kMinPart = 15;
// Points per Evaluate call: large, since f may live in another process.
constexpr uint64_t kBatch = 8192;
// Floor of a spread estimate, so that a flat half still gets a share.
constexpr double kTiny = 1e-30;

struct Node {
  uint64_t first = 0;    // first index of the node's range in the sequence
  uint64_t budget = 0;   // points of the node and its descendants
  uint64_t explore = 0;  // exploration points; 0 for a leaf
  double left_fraction = 0.5;  // volume of the first half / the node's
  size_t left = 0;             // index of the first half; the second follows
};

class MiserIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Float("explore_fraction").Default(0.1).Range(0, 1).Doc("share of a node's points spent exploring, (0, 1)"),
        P::Int("min_points").Default(60).Min(2).Doc("a node with fewer points is a leaf"),
        P::Float("dither").Default(0.05).Range(0, 0.5).Doc("cuts at 0.5 ± dither of an axis, in [0, 0.5)"),
    };
  }

  explicit MiserIntegrator(const Properties& props)
      : explore_fraction_(props.Float("explore_fraction", 0.1)),
        min_points_(props.Int("min_points", 60)),
        dither_(props.Float("dither", 0.05)) {
    if (!(explore_fraction_ > 0 && explore_fraction_ < 1))
      throw Error("property 'explore_fraction' must be in (0, 1)");
    if (min_points_ < 2) throw Error("property 'min_points' must be at least 2");
    if (!(dither_ >= 0 && dither_ < 0.5)) throw Error("property 'dither' must be in [0, 0.5)");
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckProperBox(lower, upper, d);
    if (evaluations < 2) throw Error("need at least 2 evaluations");

    Run run(*this, f, sampler, seed, d, k);
    run.Tree(lower, upper, evaluations);
    const double volume = BoxVolume(lower, upper);
    IntegrationResult result;
    result.evaluations = evaluations;
    for (uint32_t c = 0; c < k; ++c) {
      result.estimate.push_back(volume * run.mean[c]);
      result.standard_error.push_back(volume * std::sqrt(run.var[c]));
    }
    return result;
  }

 private:
  // The state of one Integrate call.
  class Run {
   public:
    Run(const MiserIntegrator& owner, Function& f, const Sampler& sampler, uint64_t seed, uint32_t d,
        uint32_t k)
        : owner_(owner), f_(f), sampler_(sampler), seed_(seed), d_(d), k_(k),
          points_(kBatch * d), values_(kBatch * k), mid_(d), fraction_(d),
          count_lo_(d), count_hi_(d), min_lo_(size_t(d) * k), max_lo_(size_t(d) * k),
          min_hi_(size_t(d) * k), max_hi_(size_t(d) * k), leaf_(k) {}

    // Builds and evaluates the tree, leaving the root's mean of f and the
    // variance of that mean in `mean` and `var`.
    void Tree(std::span<const double> lower, std::span<const double> upper, uint64_t budget) {
      nodes_.push_back(Node{0, budget});
      means_.resize(k_);
      vars_.resize(k_);
      boxes_.assign(lower.begin(), lower.end());
      boxes_.insert(boxes_.end(), upper.begin(), upper.end());
      for (size_t begin = 0; begin < nodes_.size();) {
        const size_t end = nodes_.size();
        level_begin_ = begin;
        next_boxes_.clear();
        for (size_t i = begin; i < end; ++i) Emit(i);
        Flush();
        boxes_.swap(next_boxes_);
        begin = end;
      }
      // Children follow their parents, so one backward pass combines them.
      for (size_t i = nodes_.size(); i-- > 0;) {
        const Node& node = nodes_[i];
        if (node.explore == 0) continue;
        const double p = node.left_fraction, q = 1 - p;
        for (uint32_t c = 0; c < k_; ++c) {
          const size_t a = node.left * k_ + c, b = (node.left + 1) * k_ + c;
          means_[i * k_ + c] = p * means_[a] + q * means_[b];
          vars_[i * k_ + c] = p * p * vars_[a] + q * q * vars_[b];
        }
      }
      mean.assign(means_.begin(), means_.begin() + k_);
      var.assign(vars_.begin(), vars_.begin() + k_);
    }

    std::vector<double> mean, var;

   private:
    struct Segment {
      size_t node;
      uint64_t offset;  // of the segment's first point in the node's points
      uint64_t count;
      bool last;        // the node's points end here
    };

    const double* Box(size_t node) const { return &boxes_[(node - level_begin_) * 2 * d_]; }

    // Queues node i's exploration points, or all its points if a leaf.
    void Emit(size_t i) {
      // Copies: a Flush below may add nodes and move the vector.
      const uint64_t first = nodes_[i].first, budget = nodes_[i].budget;
      const uint64_t explore = std::max(kMinPart, uint64_t(owner_.explore_fraction_ * double(budget)));
      const bool leaf = budget < uint64_t(owner_.min_points_) || budget < explore + 2 * kMinPart;
      nodes_[i].explore = leaf ? 0 : explore;
      const uint64_t total = leaf ? budget : explore;
      const double* lo = Box(i);
      const double* hi = lo + d_;
      for (uint64_t done = 0; done < total;) {
        const uint64_t take = std::min(total - done, kBatch - buffered_);
        std::span<float> out(points_.data() + buffered_ * d_, take * d_);
        sampler_.Generate(first + done, uint32_t(take), d_, seed_, out);
        MapToBox(out, std::span(lo, d_), std::span(hi, d_));
        segments_.push_back(Segment{i, done, take, done + take == total});
        buffered_ += take;
        done += take;
        if (buffered_ == kBatch) Flush();
      }
    }

    // Evaluates the queued points and feeds them to their nodes.
    void Flush() {
      if (buffered_ == 0) return;
      f_.Evaluate(std::span<const float>(points_.data(), buffered_ * d_),
                  std::span<float>(values_.data(), buffered_ * k_));
      uint64_t at = 0;
      for (const Segment& s : segments_) {
        const bool leaf = nodes_[s.node].explore == 0;
        if (s.offset == 0) leaf ? StartLeaf() : StartExploring(s.node);
        for (uint64_t p = at; p < at + s.count; ++p) leaf ? AddToLeaf(p) : Explore(p);
        at += s.count;
        if (s.last) leaf ? FinishLeaf(s.node) : Split(s.node);
      }
      segments_.clear();
      buffered_ = 0;
    }

    void StartLeaf() { leaf_.Clear(); }
    void AddToLeaf(uint64_t p) { leaf_.Add(&values_[p * k_]); }
    void FinishLeaf(size_t i) {
      for (uint32_t c = 0; c < k_; ++c) {
        means_[i * k_ + c] = leaf_.Mean(c);
        vars_[i * k_ + c] = leaf_.VarianceOfMean(c);
      }
    }

    void StartExploring(size_t i) {
      const double* lo = Box(i);
      const double* hi = lo + d_;
      for (uint32_t j = 0; j < d_; ++j) {
        const bool up = sampler_.Sample(nodes_[i].first, d_ + j, seed_) < 0.5f;
        fraction_[j] = 0.5 + (up ? owner_.dither_ : -owner_.dither_);
        mid_[j] = lo[j] + fraction_[j] * (hi[j] - lo[j]);
      }
      std::fill(count_lo_.begin(), count_lo_.end(), 0);
      std::fill(count_hi_.begin(), count_hi_.end(), 0);
      constexpr double inf = std::numeric_limits<double>::infinity();
      std::fill(min_lo_.begin(), min_lo_.end(), inf);
      std::fill(min_hi_.begin(), min_hi_.end(), inf);
      std::fill(max_lo_.begin(), max_lo_.end(), -inf);
      std::fill(max_hi_.begin(), max_hi_.end(), -inf);
    }
    void Explore(uint64_t p) {
      for (uint32_t j = 0; j < d_; ++j) {
        const bool low = double(points_[p * d_ + j]) < mid_[j];
        (low ? count_lo_ : count_hi_)[j]++;
        double* mn = (low ? min_lo_ : min_hi_).data() + size_t(j) * k_;
        double* mx = (low ? max_lo_ : max_hi_).data() + size_t(j) * k_;
        for (uint32_t c = 0; c < k_; ++c) {
          const double v = values_[p * k_ + c];
          mn[c] = std::min(mn[c], v);
          mx[c] = std::max(mx[c], v);
        }
      }
    }
    // Chooses the axis, allocates the rest of the budget and makes the halves.
    void Split(size_t i) {
      int64_t axis = -1;
      double best = std::numeric_limits<double>::infinity(), sigma_lo = 1, sigma_hi = 1;
      for (uint32_t j = 0; j < d_; ++j) {
        if (count_lo_[j] == 0 || count_hi_[j] == 0) continue;  // nothing seen on one side
        double range_lo = 0, range_hi = 0;
        for (uint32_t c = 0; c < k_; ++c) {
          range_lo += max_lo_[size_t(j) * k_ + c] - min_lo_[size_t(j) * k_ + c];
          range_hi += max_hi_[size_t(j) * k_ + c] - min_hi_[size_t(j) * k_ + c];
        }
        const double s_lo = std::pow(std::max(range_lo, kTiny), 2.0 / 3.0);
        const double s_hi = std::pow(std::max(range_hi, kTiny), 2.0 / 3.0);
        if (s_lo + s_hi < best) {
          best = s_lo + s_hi;
          axis = j;
          sigma_lo = s_lo;
          sigma_hi = s_hi;
        }
      }
      if (axis < 0) {  // no axis had points on both sides: any axis, even shares
        const float u = sampler_.Sample(nodes_[i].first, 2 * d_, seed_);
        axis = std::min<int64_t>(d_ - 1, int64_t(u * float(d_)));
      }
      Node& node = nodes_[i];
      const uint64_t rest = node.budget - node.explore;
      const uint64_t n_lo =
          kMinPart + uint64_t(double(rest - 2 * kMinPart) * sigma_lo / (sigma_lo + sigma_hi));
      const uint64_t n_hi = rest - n_lo;
      node.left_fraction = fraction_[axis];
      node.left = nodes_.size();
      const uint64_t first = node.first + node.explore;
      nodes_.push_back(Node{first, n_lo});
      nodes_.push_back(Node{first + n_lo, n_hi});
      means_.resize(nodes_.size() * k_);
      vars_.resize(nodes_.size() * k_);
      const double* lo = Box(i);
      const double* hi = lo + d_;
      for (int half = 0; half < 2; ++half) {
        const size_t at = next_boxes_.size();
        next_boxes_.insert(next_boxes_.end(), lo, lo + d_);
        next_boxes_.insert(next_boxes_.end(), hi, hi + d_);
        if (half == 0)
          next_boxes_[at + d_ + axis] = mid_[axis];  // upper bound of the lower half
        else
          next_boxes_[at + axis] = mid_[axis];  // lower bound of the upper half
      }
    }

    const MiserIntegrator& owner_;
    Function& f_;
    const Sampler& sampler_;
    uint64_t seed_;
    uint32_t d_, k_;

    std::vector<Node> nodes_;
    std::vector<double> means_, vars_;  // per node and output
    // Boxes (lower then upper corner) of the level being built and of the next.
    std::vector<double> boxes_, next_boxes_;
    size_t level_begin_ = 0;

    // Queued points and the nodes they belong to.
    std::vector<float> points_, values_;
    std::vector<Segment> segments_;
    uint64_t buffered_ = 0;

    // The exploring node: its cuts and, per axis, side and output, the
    // number of points and the range of f seen.
    std::vector<double> mid_, fraction_;
    std::vector<uint64_t> count_lo_, count_hi_;
    std::vector<double> min_lo_, max_lo_, min_hi_, max_hi_;
    // The leaf being sampled.
    RunningMoments leaf_;
  };

  double explore_fraction_;
  int64_t min_points_;
  double dither_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::MiserIntegrator>(registrar, "miser", "1.0.0",
                                        "recursive stratified sampling (MISER, Press & Farrar)");
}
