// The strength of a linear family's weight regularisation (records/families.h
// Family::regularisation), chosen by validation on the training records (issue 22).
//
// The training samples (scored windows of the training records, in order) are cut into K = 5
// contiguous time blocks; the normal equations are accumulated per block (G_b = A_bᵀA_b,
// h_b = A_bᵀb_b, b_bᵀb_b). For each candidate strength λ = ρ · tr(G)/tr(R),
// ρ ∈ {0, 10⁻⁶, 10⁻⁵, …, 10²}, and each block b the weights are solved without the block,
// w = NNLS(G − G_b + λR, h − h_b), and the block's squared error is wᵀG_b w − 2h_bᵀw + b_bᵀb_b.
// The chosen strength is the largest ρ, going up from the one with the least cross-validated error,
// whose extra error over that one is not larger than its standard error across the blocks (the
// paired "one standard error" rule): the strongest regularisation the data cannot tell from the
// best — what keeps a Preisach density that a major loop does not determine smooth instead of a
// sparse artefact. A family with several candidate penalties (the Preisach grid: roughness along
// the centre or over the triangle) has the one kept that the records contradict less
// (ChoosePenalty). Deterministic (a fixed order of fixed-size sums).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace pz::records {

/// Normal equations of the training samples, per contiguous time block.
struct BlockedNormalEquations {
  std::vector<Eigen::MatrixXd> G;  ///< AᵀA of each block (full symmetric)
  std::vector<Eigen::VectorXd> h;  ///< Aᵀb
  std::vector<double> bb;          ///< bᵀb
  std::vector<size_t> samples;     ///< samples of each block
};

/// Accumulates the normal equations of rows given one at a time into eq's blocks (eq.G.size()
/// contiguous blocks of `samples` rows: row i goes to block i · blocks / samples). Rows are
/// gathered in chunks of 256 of one block and added as rank-k updates (a level-3 product, several
/// times faster than a rank-1 update per row on ~100 columns). Finish() symmetrises G.
class NormalEquationsBuilder {
 public:
  /// Zeroes eq's blocks at `columns` unknowns.
  NormalEquationsBuilder(BlockedNormalEquations& eq, size_t columns, size_t samples);
  /// The next row's `columns` entries, to fill before Add.
  double* Row();
  /// Adds the row filled through Row() with its target.
  void Add(double target);
  void Finish();
  /// Rows a caller sums itself (a structured family, records/preisach_normal.h): the block of the
  /// row `ahead` rows after the next one.
  size_t BlockAhead(size_t ahead) const;
  /// Adds the sums of the next `rows` rows, every one of block `block` (BlockAhead): their AᵀA
  /// (its lower triangle is used), Aᵀb and bᵀb. Throws std::logic_error when they are not.
  void AddSums(size_t block, const Eigen::MatrixXd& G, const Eigen::VectorXd& h, double bb,
               size_t rows);

 private:
  void Flush();
  BlockedNormalEquations& eq_;
  size_t samples_, index_ = 0, block_ = 0;
  Eigen::MatrixXd A_;  ///< columns × chunk
  Eigen::VectorXd b_;
  Eigen::Index filled_ = 0;
};

/// What the validation chose (reported by `piezoid fit`).
struct WeightValidation {
  bool used = false;              ///< the family has a regularisation
  double lambda = 0;              ///< the chosen λ (absolute, against the sum of squared errors)
  double relative = 0;            ///< the chosen ρ = λ tr(R) / tr(G)
  std::vector<double> relatives;  ///< the candidates ρ
  std::vector<double> cv_rmse;    ///< their cross-validated RMSE [response unit]
  int folds = 0;
  /// ChoosePenalty: the penalty kept (its index among the candidates and name), and, with more
  /// than one candidate, the strength they were compared at and each one's CV RMSE there.
  size_t penalty = 0;
  std::string penalty_name;
  double compared_at = 0;
  std::vector<std::string> candidates;
  std::vector<double> candidates_cv_rmse;
  /// The chosen strength's squared error on each left-out block (in block order): what a choice
  /// among resolutions compares (ChooseResolution).
  std::vector<double> block_sse;
  std::string Describe() const;  ///< "ρ = 1e-3 (λ = …) by 5-fold blocked cross-validation: …"
};

/// A resolution (a Preisach grid's levels) chosen by the same blocked cross-validation (issue 37):
/// each candidate's CV error at its own validated penalty and strength, and the fewest levels whose
/// extra error over the best one's is not larger than its standard error across the blocks (the
/// paired one-standard-error rule of ChooseStrength).
struct ResolutionChoice {
  bool used = false;
  std::string what = "levels";       ///< what the candidates count
  std::vector<int> candidates;       ///< ascending
  std::vector<double> cv_rmse;       ///< [response unit]; +inf where the records cannot support it
  std::vector<std::string> refused;  ///< "" or why a candidate was not tried (the training records)
  size_t best = 0, chosen = 0;
  int value() const { return candidates.at(chosen); }
  /// "28 levels by 5-fold blocked cross-validation (one standard error from the best, 40): CV RMSE
  /// 12 → …".
  std::string Describe() const;
};

/// The rule above over candidates in ascending order (validations[i].block_sse; an empty one: a
/// refused candidate). Throws std::logic_error when every candidate is refused.
ResolutionChoice ChooseResolution(const std::vector<int>& candidates,
                                  const std::vector<WeightValidation>& validations,
                                  const std::vector<std::string>& refused);

/// The number of time blocks.
inline constexpr int kValidationBlocks = 5;
/// Threads of the blocks' solves where the unknowns are many (records/nnls.h kIncrementalNnlsFrom).
inline constexpr int kValidationThreads = 2;

/// Chooses λ for the regularisation R (m×m) by the rule above. Throws InputError when a block is
/// empty (fewer training samples than blocks).
WeightValidation ChooseStrength(const BlockedNormalEquations& eq, const Eigen::MatrixXd& R);
/// How ChooseStrength picks among the candidates.
struct StrengthRule {
  /// True: the rule above (the first candidate above the best whose extra error exceeds its
  /// standard error ends the climb). False: the largest ρ above the best that passes, wherever it
  /// is (a CV curve flat within its noise but not monotone).
  bool contiguous = true;
  /// > 0: a candidate also passes when its CV RMSE is within this share of the best's (an extra
  /// error too small to matter, however consistent across the blocks: the blocks of one periodic
  /// record agree on a difference that only extrapolation would show).
  double rmse_tolerance = 0;
};
/// Several candidate penalties R_k (names: for the report): each one's strength by ChooseStrength,
/// then the one kept whose CV RMSE is the lowest at the first candidate strength ρ above every
/// one's chosen strength (the largest candidate if none is above): the first strength at which the
/// training records object to a penalty, where its CV error says how much it contradicts what the
/// records identify — a Preisach density's interior that a major loop leaves open is filled in by
/// the penalty the branches contradict less. Ties keep the first. One candidate: ChooseStrength.
WeightValidation ChoosePenalty(const BlockedNormalEquations& eq,
                               const std::vector<Eigen::MatrixXd>& Rs,
                               const std::vector<std::string>& names);
/// The same with the candidates λ = ρ · scale (R penalising part of the unknowns only: the scale
/// is then the trace of that part of G over tr(R)) and the rule `rule`.
WeightValidation ChooseStrength(const BlockedNormalEquations& eq, const Eigen::MatrixXd& R,
                                double scale, const StrengthRule& rule);

/// The roughness of a creep spectrum's n weights (log-spaced relaxation times,
/// model/effect_library.h `creep-spectrum`) across log-time: the first differences of neighbouring
/// weights, D (n−1 × n), whose penalty ‖D w‖² = wᵀDᵀD w vanishes on equal weights per decade — log
/// creep, the limit the penalty shrinks a spectrum towards — and grows with a spectrum's
/// raggedness.
Eigen::MatrixXd SpectrumRoughness(size_t n);

}  // namespace pz::records
