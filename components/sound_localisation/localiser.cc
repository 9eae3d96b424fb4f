#include "sound_localisation/localiser.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sarmap {
namespace sound {

double InverseNormalTail(double p) {
  // Q(t) = erfc(t / sqrt 2) / 2 is decreasing: bisection.
  double lo = -10, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(mid / std::sqrt(2.0)) > p)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

DoaKind ResolveKind(const ArrayGeometry& g, const std::string& search) {
  if (search == "1d") {
    if (!g.is_linear())
      throw std::invalid_argument("search 1d is for linear arrays; '" + g.name + "' is " +
                                  g.geometry);
    return DoaKind::kAngle1d;
  }
  if (g.is_linear() && search != "auto")
    throw std::invalid_argument("a linear array ('" + g.name +
                                "') only gives the angle to its axis: use search 1d");
  if (search == "azimuth") return DoaKind::kAzimuth;
  if (search == "azimuth_elevation") return DoaKind::kAzimuthElevation;
  return g.natural_kind();
}

Localiser::Localiser(ArrayGeometry geometry, LocaliserOptions options,
                     std::unique_ptr<SensorModel> sensor_model)
    : geometry_(std::move(geometry)),
      options_(std::move(options)),
      sensor_model_(std::move(sensor_model)),
      kind_(ResolveKind(geometry_, options_.search)),
      stft_(geometry_.num_mics(), options_.fft_size, options_.hop_size),
      tracker_(geometry_, kind_, options_.tracker) {
  if (!sensor_model_) sensor_model_ = SensorModel::Constant(3.0);
  if (options_.method == "esprit" && geometry_.UniformSpacing() <= 0)
    throw std::invalid_argument("method esprit needs a uniform linear array; '" + geometry_.name +
                                "' is not one");
  const double fs = geometry_.sample_rate_hz;
  bin_lo_ =
      std::max(1, static_cast<int>(std::ceil(options_.min_frequency_hz * options_.fft_size / fs)));
  bin_hi_ =
      std::min(options_.fft_size / 2 - 1,
               static_cast<int>(std::floor(options_.max_frequency_hz * options_.fft_size / fs)));
  if (bin_hi_ < bin_lo_) throw std::invalid_argument("frequency band is empty at this sample rate");
  block_frames_ =
      std::max(1, static_cast<int>(std::round(options_.block_s * fs / options_.hop_size)));
  search_.kind = kind_;
  search_.coarse_step_deg = options_.coarse_step_deg;
  search_.fine_step_deg = options_.fine_step_deg;
  search_.min_elevation_deg = options_.min_elevation_deg;
  search_.max_elevation_deg = options_.max_elevation_deg;
  search_.max_sources = options_.max_sources;
  search_.min_separation_deg = options_.min_separation_deg;
  search_.min_peak_ratio = options_.min_peak_ratio;
  current_ = MakeStatistics();
  current_band_ = MakeStatistics();
  band_grid_units_ = SearchGridUnits(geometry_, search_);
  if (options_.detection == "cfar") {
    if (options_.method != "srp_phat")
      throw std::invalid_argument("detection cfar needs method srp_phat");
    correlation_ = std::make_unique<CorrelationSrp>(geometry_, options_.fft_size, bin_lo_, bin_hi_);
    grid_units_ = SearchGridUnits(geometry_, search_);
    correlation_->PrepareGrid(grid_units_);
    // Bonferroni: P(max over G Gaussian values > t) <= G Q(t) = false_alarm_probability.
    detection_threshold_ = InverseNormalTail(options_.false_alarm_probability / grid_units_.size());
  }
  noise_.assign(bin_hi_ - bin_lo_ + 1,
                Eigen::MatrixXcd::Zero(geometry_.num_mics(), geometry_.num_mics()));
}

BlockStatistics Localiser::MakeStatistics() const {
  BlockStatistics s;
  s.fft_size = options_.fft_size;
  s.sample_rate_hz = geometry_.sample_rate_hz;
  s.bin_lo = bin_lo_;
  s.bin_hi = bin_hi_;
  s.Reset(geometry_.num_mics());
  return s;
}

void Localiser::DirectPathMask(const Eigen::MatrixXcf& spectra,
                               std::vector<Eigen::MatrixXcd>* state,
                               std::vector<char>* mask) const {
  const int m = geometry_.num_mics();
  const int nb = bin_hi_ - bin_lo_ + 1;
  if (static_cast<int>(state->size()) != nb) state->assign(nb, Eigen::MatrixXcd::Zero(m, m));
  mask->assign(nb, 1);
  const double a = options_.direct_path_smoothing;
  Eigen::VectorXcd x(m);
  for (int k = bin_lo_; k <= bin_hi_; ++k) {
    for (int i = 0; i < m; ++i) x(i) = ComplexD(spectra(k, i).real(), spectra(k, i).imag());
    (*state)[k - bin_lo_] = a * (*state)[k - bin_lo_] + (1 - a) * (x * x.adjoint());
  }
  if (options_.direct_path_threshold <= 0) return;
  for (int b = 0; b < nb; ++b) {
    // Sum with the neighbouring bins: a rank-1 test needs more than one snapshot.
    Eigen::MatrixXcd r = (*state)[b];
    if (b > 0) r += (*state)[b - 1];
    if (b + 1 < nb) r += (*state)[b + 1];
    const double tr = r.trace().real();
    const double ratio = tr > 0 ? r.squaredNorm() / (tr * tr) : 0.0;
    (*mask)[b] = ratio >= options_.direct_path_threshold;
  }
}

void Localiser::OnsetMask(const Eigen::MatrixXcf& spectra, std::vector<double>* level,
                          std::vector<char>* mask) const {
  if (options_.onset_rise_db <= 0) return;
  const int nb = bin_hi_ - bin_lo_ + 1;
  const bool first = static_cast<int>(level->size()) != nb;
  if (first) level->assign(nb, 0.0);
  // level_k <- a level_k + (1 - a) p_k, a = exp(-hop / memory); bin used when
  // p_k > level_k * 10^(rise / 10) (compared before the update).
  const double hop_s = static_cast<double>(options_.hop_size) / geometry_.sample_rate_hz;
  const double a = std::exp(-hop_s / options_.onset_memory_s);
  const double rise = std::pow(10.0, options_.onset_rise_db / 10);
  for (int b = 0; b < nb; ++b) {
    const double p = spectra.row(bin_lo_ + b).squaredNorm();
    if (first || !(p > (*level)[b] * rise)) (*mask)[b] = 0;
    (*level)[b] = first ? p : a * (*level)[b] + (1 - a) * p;
  }
}

void Localiser::Accumulate(const Eigen::MatrixXcf& spectra, BlockStatistics* stats,
                           const std::vector<char>* mask) const {
  const int m = geometry_.num_mics();
  Eigen::VectorXcd x(m), y(m);
  for (int k = bin_lo_; k <= bin_hi_; ++k) {
    if (mask && !(*mask)[k - bin_lo_]) continue;
    for (int i = 0; i < m; ++i) {
      x(i) = ComplexD(spectra(k, i).real(), spectra(k, i).imag());
      const double mag = std::abs(x(i));
      y(i) = mag > 1e-20 ? x(i) / mag : ComplexD(0, 0);
    }
    stats->raw[k - bin_lo_].noalias() += x * x.adjoint();
    stats->phat[k - bin_lo_].noalias() += y * y.adjoint();
  }
  ++stats->num_frames;
}

void Localiser::AccumulateWeighted(const Eigen::MatrixXcf& spectra, BlockStatistics* stats,
                                   const std::vector<char>* mask, BlockStatistics* plain) const {
  // Each bin's PHAT term weighted by its share of power above the noise (Wiener-like
  // 1 - noise / power, noise = the noise covariance's trace): noise-only bins add ~nothing, so
  // a block's map is its sounds', whatever share of its frames they fill. `plain` (optional)
  // gets the same frame unweighted, as Accumulate adds it.
  const int m = geometry_.num_mics();
  Eigen::VectorXcd x(m), y(m);
  Eigen::MatrixXcd xx(m, m), yy(m, m);
  for (int k = bin_lo_; k <= bin_hi_; ++k) {
    if (mask && !(*mask)[k - bin_lo_]) continue;
    double power = 0;
    for (int i = 0; i < m; ++i) {
      x(i) = ComplexD(spectra(k, i).real(), spectra(k, i).imag());
      power += std::norm(x(i));
    }
    const double noise = noise_frames_ > 0 ? noise_[k - bin_lo_].trace().real() : 0.0;
    const double w = power > 0 ? std::max(0.0, 1.0 - noise / power) : 0.0;
    for (int i = 0; i < m; ++i) {
      const double mag = std::abs(x(i));
      y(i) = mag > 1e-20 ? x(i) / mag : ComplexD(0, 0);
    }
    xx.noalias() = x * x.adjoint();
    stats->raw[k - bin_lo_] += xx;
    if (plain) {
      yy.noalias() = y * y.adjoint();
      plain->raw[k - bin_lo_] += xx;
      plain->phat[k - bin_lo_] += yy;
      if (w > 0) stats->phat[k - bin_lo_] += w * yy;
    } else if (w > 0) {
      stats->phat[k - bin_lo_].noalias() += w * (y * y.adjoint());
    }
  }
  ++stats->num_frames;
  if (plain) ++plain->num_frames;
}

void Localiser::ResetStream() {
  stft_.Reset();
  stream_offset_ = samples_seen_;
}

void Localiser::SkipSamples(int64_t samples) {
  if (samples <= 0) return;
  stream_offset_ += samples;
  samples_seen_ += samples;
}

void Localiser::Push(const int16_t* data, int frames, int block_channels,
                     std::vector<LocaliserOutput>* out) {
  geometry_.CheckChannels(block_channels);
  stft_.PushInterleaved(
      data, frames, block_channels, geometry_.channel_map,
      [&](const Eigen::MatrixXcf& s, int64_t end) { OnFrame(s, stream_offset_ + end, out); });
  samples_seen_ += frames;
}

void Localiser::PushFloat(const std::vector<std::vector<float>>& ch, size_t begin, size_t count,
                          std::vector<LocaliserOutput>* out) {
  stft_.PushFloat(ch, begin, count, [&](const Eigen::MatrixXcf& s, int64_t end) {
    OnFrame(s, stream_offset_ + end, out);
  });
  samples_seen_ += count;
}

void Localiser::OnFrame(const Eigen::MatrixXcf& spectra, int64_t end_sample,
                        std::vector<LocaliserOutput>* out) {
  const int m = geometry_.num_mics();
  double energy = 0;
  for (int k = bin_lo_; k <= bin_hi_; ++k) energy += spectra.row(k).squaredNorm();
  const double hop_s = static_cast<double>(options_.hop_size) / geometry_.sample_rate_hz;
  if (noise_floor_ < 0) noise_floor_ = energy;
  const bool active = energy > noise_floor_ * std::pow(10.0, options_.activity_snr_db / 10);
  if (energy < noise_floor_)
    noise_floor_ = energy;
  else
    noise_floor_ *= std::pow(10.0, options_.noise_rise_db_per_s * hop_s / 10);
  noise_floor_ = std::max(noise_floor_, 1e-20);
  DirectPathMask(spectra, &smoothed_, &mask_);
  OnsetMask(spectra, &onset_level_, &mask_);
  const bool cfar = correlation_ != nullptr;
  current_active_ += active;
  if (cfar) {
    // Band peaks keep their own statistics: the loud frames, unweighted, as with the energy
    // gate (their coherence threshold is calibrated on those).
    AccumulateWeighted(spectra, &current_, &mask_,
                       options_.band_hz > 0 && active ? &current_band_ : nullptr);
  } else if (active) {
    Accumulate(spectra, &current_, &mask_);
  }
  if (!active) {
    const double alpha = std::max(hop_s / options_.noise_average_s, 1.0 / (noise_frames_ + 1));
    Eigen::VectorXcd x(m);
    for (int k = bin_lo_; k <= bin_hi_; ++k) {
      for (int i = 0; i < m; ++i) x(i) = ComplexD(spectra(k, i).real(), spectra(k, i).imag());
      noise_[k - bin_lo_] = (1 - alpha) * noise_[k - bin_lo_] + alpha * (x * x.adjoint());
    }
    ++noise_frames_;
  }
  if (++current_frames_ < block_frames_) return;

  window_.push_back(current_);
  window_total_frames_.push_back(current_frames_);
  window_active_.push_back(current_active_);
  current_ = MakeStatistics();
  if (cfar && options_.band_hz > 0) {
    window_band_.push_back(current_band_);
    current_band_ = MakeStatistics();
    while (static_cast<int>(window_band_.size()) > options_.window_blocks) window_band_.pop_front();
  }
  current_frames_ = 0;
  current_active_ = 0;
  while (static_cast<int>(window_.size()) > options_.window_blocks) {
    window_.pop_front();
    window_total_frames_.pop_front();
    window_active_.pop_front();
  }
  BlockStatistics stats = MakeStatistics();
  int total = 0, active_frames = 0;
  for (size_t i = 0; i < window_.size(); ++i) {
    stats.Add(window_[i]);
    total += window_total_frames_[i];
    active_frames += window_active_[i];
  }
  LocaliserOutput o;
  o.end_sample = end_sample;
  o.centre_sample =
      end_sample - static_cast<int64_t>(total) * options_.hop_size / 2 - options_.fft_size / 2;
  const bool loud = active_frames >= std::max(2.0, options_.min_active_fraction * total);
  std::vector<TrackMeasurement> measurements;
  std::vector<DoaEstimate> estimates;
  if (cfar) {
    if (noise_frames_ > 10) stats.noise = noise_;
    estimates = Detect(stats);
    if (options_.band_hz > 0 && loud) {
      // Narrowband sources beside the detected ones: band peaks of the loud frames.
      BlockStatistics band_stats = MakeStatistics();
      for (const BlockStatistics& b : window_band_) band_stats.Add(b);
      if (noise_frames_ > 10) band_stats.noise = noise_;
      if (options_.noise_subtraction > 0 && !band_stats.noise.empty())
        band_stats = SubtractNoiseCrossSpectra(band_stats, options_.noise_subtraction);
      if (band_stats.num_frames > 0) AddBandPeaks(band_stats, &estimates);
    }
    o.active = !estimates.empty();
  } else {
    o.active = loud;
    if (o.active) {
      if (noise_frames_ > 10) stats.noise = noise_;
      estimates = Estimate(stats);
    }
  }
  {
    for (DoaEstimate& e : estimates) {
      // The cfar detector has decided already.
      if (!cfar && e.confidence < options_.min_confidence) continue;
      LocalisedDirection d;
      d.direction = e.direction;
      d.covariance = sensor_model_->Apply(kind_, &d.direction);
      d.power = e.power;
      d.confidence = e.confidence;
      d.band = e.band;
      d.band_hz = e.band_hz;
      o.directions.push_back(d);
      TrackMeasurement tm;
      tm.direction = d.direction;
      tm.covariance = d.covariance;
      tm.power = d.power;
      tm.confidence = d.confidence;
      tm.primary = measurements.empty();
      measurements.push_back(tm);
    }
  }
  o.tracks =
      tracker_.Update(static_cast<double>(end_sample) / geometry_.sample_rate_hz, measurements);
  out->push_back(std::move(o));
}

std::vector<DoaEstimate> Localiser::Estimate(const BlockStatistics& block) const {
  if (block.num_frames == 0) return {};
  const std::string& method = options_.method;
  BlockStatistics subtracted;
  const bool subtract =
      method == "srp_phat" && options_.noise_subtraction > 0 && !block.noise.empty();
  if (subtract) subtracted = SubtractNoiseCrossSpectra(block, options_.noise_subtraction);
  const BlockStatistics& stats = subtract ? subtracted : block;
  if (method == "gcc_phat") return GccPhatDirection(geometry_, stats, kind_);
  if (method == "esprit")
    return Esprit(geometry_, stats, options_.music_num_sources, options_.min_separation_deg);
  if (method == "srp_phat" && options_.band_hz > 0) return EstimateWithBands(stats);
  if (method == "srp_phat") {
    SrpPhat srp(geometry_, stats);
    auto peaks = FindPeaks(geometry_, search_, std::ref(srp));
    for (auto& p : peaks) p.confidence = std::clamp(p.power, 0.0, 1.0);
    return peaks;
  }
  Music music(geometry_, stats, options_.music_num_sources, method == "gevd_music");
  double mean = 0;
  auto peaks = FindPeaks(geometry_, search_, std::ref(music), &mean);
  for (auto& p : peaks)
    p.confidence = p.power > 0 ? std::clamp(1.0 - mean / p.power, 0.0, 1.0) : 0.0;
  return peaks;
}

bool Localiser::IsGridLocalMax(const std::vector<double>& values, size_t index) const {
  // Grid order of SearchGridUnits: elevation-major, azimuth fastest.
  const double step = options_.coarse_step_deg;
  const bool wrap = kind_ != DoaKind::kAngle1d;
  const int na = wrap ? static_cast<int>(std::round(360.0 / step))
                      : static_cast<int>(std::floor(180.0 / step + 1e-9)) + 1;
  const int ne = static_cast<int>(values.size()) / na;
  const int e = static_cast<int>(index) / na, a = static_cast<int>(index) % na;
  for (int de = -1; de <= 1; ++de)
    for (int da = -1; da <= 1; ++da) {
      if (!de && !da) continue;
      const int ee = e + de;
      int aa = a + da;
      if (ee < 0 || ee >= ne) continue;
      if (wrap)
        aa = (aa + na) % na;
      else if (aa < 0 || aa >= na)
        continue;
      if (values[ee * na + aa] > values[index]) return false;
    }
  return true;
}

std::vector<DoaEstimate> Localiser::Detect(const BlockStatistics& block) {
  if (block.num_frames == 0) return {};
  BlockStatistics subtracted;
  const bool subtract = options_.noise_subtraction > 0 && !block.noise.empty();
  if (subtract) subtracted = SubtractNoiseCrossSpectra(block, options_.noise_subtraction);
  const BlockStatistics& stats = subtract ? subtracted : block;
  correlation_->SetBlock(stats);
  std::vector<double> values;
  correlation_->EvaluateGrid(&values);
  const size_t g = values.size();
  // Incoherent noise: each PHAT cross term is cos of a uniform phase (variance 1/2), pairs
  // uncorrelated, so the value's variance is 1 / (2 N K pairs): the prior before any noise block.
  const double prior_var =
      1.0 / (2.0 * block.num_frames * correlation_->num_bins() * correlation_->num_pairs());
  if (noise_mean_.size() != g) {
    noise_mean_.assign(g, 0.0);
    noise_var_.assign(g, prior_var);
    noise_map_blocks_ = 0;
  }
  const std::vector<double> unsuppressed = values;
  // A further source is a peak of its own in the block's map, not a shoulder of one found.
  std::vector<char> local_max(g, 1);
  if (options_.secondary_local_max && options_.max_sources > 1)
    for (size_t i = 0; i < g; ++i) local_max[i] = IsGridLocalMax(unsuppressed, i);
  std::vector<DoaEstimate> found;
  std::vector<char> excluded(g, 0);
  const double half_width = options_.suppression_samples > 0
                                ? options_.suppression_samples
                                : geometry_.sample_rate_hz /
                                      (2 * (options_.min_frequency_hz + options_.max_frequency_hz));
  const double min_sep = DegToRad(options_.min_separation_deg);
  while (static_cast<int>(found.size()) < options_.max_sources) {
    // Among the directions whose standardised value passes the threshold, the strongest value
    // first (CLEAN's order: a source's side and grating lobes are weaker than the source).
    size_t best = g;
    double best_z = -INFINITY, best_value = -INFINITY;
    for (size_t i = 0; i < g; ++i) {
      if (excluded[i] || (!found.empty() && options_.secondary_local_max && !local_max[i]))
        continue;
      // Floor: after digital silence the learnt spread is ~0 and any dither would stand out.
      const double z =
          (values[i] - noise_mean_[i]) / std::sqrt(std::max(noise_var_[i], 1e-4 * prior_var));
      const bool passes = z >= detection_threshold_;
      if (passes ? (values[i] > best_value || best_z < detection_threshold_)
                 : (best_z < detection_threshold_ && z > best_z)) {
        best_z = z;
        best = i;
        if (passes) best_value = values[i];
      }
    }
    if (best == g || best_z < detection_threshold_) break;
    // Refine on the (suppressed) spectrum by hill-climbing with halving steps.
    Direction d = geometry_.FromUnit(kind_, grid_units_[best]);
    double v = (*correlation_)(grid_units_[best]);
    const double lo_el = DegToRad(options_.min_elevation_deg),
                 hi_el = DegToRad(options_.max_elevation_deg);
    for (double step = DegToRad(options_.coarse_step_deg) / 2;
         step >= DegToRad(options_.fine_step_deg) * 0.999; step /= 2) {
      for (int iter = 0; iter < 4; ++iter) {
        Direction best_d = d;
        double best_v = v;
        for (int de = -1; de <= 1; ++de)
          for (int da = -1; da <= 1; ++da) {
            if ((!de && !da) || (kind_ != DoaKind::kAzimuthElevation && de)) continue;
            Direction t{d.azimuth_rad + da * step, d.elevation_rad + de * step};
            if (kind_ == DoaKind::kAngle1d)
              t.azimuth_rad = std::clamp(t.azimuth_rad, 0.0, M_PI);
            else
              t.azimuth_rad = WrapAngle(t.azimuth_rad);
            if (kind_ == DoaKind::kAzimuthElevation)
              t.elevation_rad = std::clamp(t.elevation_rad, lo_el, hi_el);
            const double tv = (*correlation_)(geometry_.Unit(kind_, t));
            if (tv > best_v) {
              best_v = tv;
              best_d = t;
            }
          }
        if (best_v <= v) break;
        d = best_d;
        v = best_v;
      }
    }
    DoaEstimate e;
    e.direction = d;
    e.power = v;
    e.confidence = std::clamp(unsuppressed[best], 0.0, 1.0);
    found.push_back(e);
    const Eigen::Vector3d u = geometry_.Unit(kind_, d);
    if (options_.suppression == "clean")
      correlation_->Subtract(u);
    else
      correlation_->Suppress(u, half_width);
    correlation_->EvaluateGrid(&values);
    for (size_t i = 0; i < g; ++i)
      if (AngularDistanceRad(geometry_, kind_, geometry_.FromUnit(kind_, grid_units_[i]), d) <
          min_sep)
        excluded[i] = 1;
  }
  // Noise statistics from blocks without a detection: exponential averages, the prior counting
  // as one block for the variance. With steady_s, blocks with a detection teach them too, at
  // that slower rate: what is heard without pause for much longer than anyone talks (a fan, the
  // robot's own motors) becomes background.
  const double block_s = options_.block_s;
  double a_mean = 0, a_var = 0;
  if (found.empty()) {
    a_mean = std::max(block_s / options_.noise_map_s, 1.0 / (noise_map_blocks_ + 1));
    a_var = std::max(block_s / options_.noise_map_s, 1.0 / (noise_map_blocks_ + 2));
    ++noise_map_blocks_;
  } else if (options_.steady_s > 0) {
    // The mean only: the spread of what stands out is not the noise's.
    a_mean = block_s / options_.steady_s;
  }
  if (a_mean > 0)
    for (size_t i = 0; i < g; ++i) {
      const double dev = unsuppressed[i] - noise_mean_[i];
      noise_var_[i] = (1 - a_var) * noise_var_[i] + a_var * dev * dev;
      noise_mean_[i] += a_mean * dev;
    }
  return found;
}

std::vector<DoaEstimate> Localiser::EstimateWithBands(const BlockStatistics& stats) const {
  // One steering pass over the coarse grid gives the broadband spectrum and every band's.
  const BandSrpPhat bands(geometry_, stats, options_.band_hz);
  const std::vector<Eigen::Vector3d>& units = band_grid_units_;
  const int nb = bands.num_bands();
  std::vector<double> total(units.size()), per_band;
  std::vector<std::vector<double>> band_values(nb, std::vector<double>(units.size()));
  for (size_t i = 0; i < units.size(); ++i) {
    total[i] = bands.Evaluate(units[i], &per_band);
    for (int b = 0; b < nb; ++b) band_values[b][i] = per_band[b];
  }
  const SrpPhat srp(geometry_, stats);
  std::vector<DoaEstimate> out = FindPeaksOnGrid(geometry_, search_, total, std::cref(srp));
  for (auto& p : out) p.confidence = std::clamp(p.power, 0.0, 1.0);
  AddBandPeaks(bands, band_values, &out);
  return out;
}

void Localiser::AddBandPeaks(const BlockStatistics& stats, std::vector<DoaEstimate>* out) const {
  const BandSrpPhat bands(geometry_, stats, options_.band_hz);
  const std::vector<Eigen::Vector3d>& units = band_grid_units_;
  const int nb = bands.num_bands();
  std::vector<double> per_band;
  std::vector<std::vector<double>> band_values(nb, std::vector<double>(units.size()));
  for (size_t i = 0; i < units.size(); ++i) {
    bands.Evaluate(units[i], &per_band);
    for (int b = 0; b < nb; ++b) band_values[b][i] = per_band[b];
  }
  AddBandPeaks(bands, band_values, out);
}

void Localiser::AddBandPeaks(const BandSrpPhat& bands,
                             const std::vector<std::vector<double>>& band_values,
                             std::vector<DoaEstimate>* out) const {
  const std::vector<Eigen::Vector3d>& units = band_grid_units_;
  const int nb = bands.num_bands();
  // Bands by their best coarse value; each adds its refined peak when it is coherent enough and
  // far from every direction already reported.
  std::vector<std::pair<double, int>> order;
  std::vector<size_t> best_index(nb, 0);
  for (int b = 0; b < nb; ++b) {
    if (bands.band_tonality(b) < options_.band_min_tonality) continue;
    const auto& v = band_values[b];
    best_index[b] = static_cast<size_t>(std::max_element(v.begin(), v.end()) - v.begin());
    if (v[best_index[b]] >= options_.band_min_coherence) order.emplace_back(v[best_index[b]], b);
  }
  std::sort(order.begin(), order.end(), std::greater<>());
  const double min_sep = DegToRad(options_.min_separation_deg);
  SearchOptions one = search_;
  one.max_sources = 1;
  int added = 0;
  auto far_from_all = [&](const Direction& d) {
    for (const auto& e : *out)
      if (AngularDistanceRad(geometry_, kind_, e.direction, d) < min_sep) return false;
    return true;
  };
  for (const auto& [value, b] : order) {
    if (added >= options_.band_max_sources) break;
    if (!far_from_all(geometry_.FromUnit(kind_, units[best_index[b]]))) continue;
    auto peak =
        FindPeaksOnGrid(geometry_, one, band_values[b],
                        [&bands, b = b](const Eigen::Vector3d& u) { return bands.Band(u, b); });
    if (peak.empty() || !far_from_all(peak.front().direction)) continue;
    DoaEstimate e = peak.front();
    e.confidence = std::clamp(e.power, 0.0, 1.0);
    e.band = b;
    e.band_hz = bands.band_centre_hz(b);
    out->push_back(e);
    ++added;
  }
}

}  // namespace sound
}  // namespace sarmap
