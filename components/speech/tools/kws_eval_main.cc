// sarmap-log-kws-eval: recall / false-alarm curve of keyword spotting on simulated calls for
// help (espeak-ng) in noise and other talkers, over a sweep of detection thresholds.
#include <cstdio>

#include "common/args.h"
#include "common/logging.h"
#include "common/robot_config.h"
#include "speech/testing/kws_evaluation.h"

using namespace sarmap;

int main(int argc, char** argv) {
  return common::RunMain("sarmap-log-kws-eval", [&]() {
    speech::KwsEvalOptions o;
    o.data_dir = SARMAP_DATA_DIR;
    std::string thresholds = "1e-10,1e-20,1e-30,1e-40", keyword_list = "help,rescue,assist,here";
    double min_conf = 0.0;
    std::string confidences = "0,0.3,0.5,0.6,0.7,0.8,0.9";
    std::string verify = "none", cmn = "current";
    bool full_utt = false;
    speech::KeywordOptions shape;  // verification and call-shape settings (defaults: off)
    std::string split_thresholds;
    common::ArgParser p("sarmap-log-kws-eval",
                        "Keyword-spotting recall and false alarms vs threshold.");
    p.AddFlag("--calls", &o.num_calls, "number of simulated calls");
    p.AddFlag("--negative-minutes", &o.negative_minutes, "minutes of other speech and noise");
    p.AddFlag("--snr-db", &o.call_snr_db, "call to background ratio");
    p.AddFlag("--babble-db", &o.babble_db, "other talkers relative to the call (positives)");
    p.AddFlag("--data-dir", &o.data_dir, "shared data directory (real other speech)");
    p.AddFlag("--thresholds", &thresholds, "comma-separated thresholds to sweep");
    p.AddFlag("--keywords", &keyword_list,
              "comma-separated keyword list (all spotted, 'help' scored)");
    p.AddFlag("--min-confidence", &min_conf, "confidence cut applied to detections");
    p.AddFlag("--confidences", &confidences,
              "posterior cuts reported for each threshold (a post-filter)");
    p.AddFlag("--verify", &verify,
              "second stage: acoustic (forced alignment vs phone loop), lm, grammar or none");
    p.AddFlag("--cmn", &cmn, "PocketSphinx CMN: current, prior or none");
    p.AddSwitch("--full-utterance", &full_utt, "process utterances as one block");
    p.AddFlag("--verify-min-llr", &shape.verify_min_llr,
              "with --verify acoustic: per-frame LLR threshold");
    std::string max_utterances = "0";
    p.AddFlag(
        "--max-utterances-s", &max_utterances,
        "comma-separated: longest utterance that can hold a call (0: any), swept as a post-filter");
    std::string call_joins = "0";
    p.AddFlag("--call-joins-s", &call_joins,
              "comma-separated: utterances separated by less non-speech are one call for the "
              "call-shape rule "
              "(call_join_s), swept as a post-filter");
    p.AddFlag("--min-utterance-fraction", &shape.min_utterance_fraction,
              "hit covers at least this of its utterance");
    p.AddFlag("--min-duration-s", &shape.min_duration_s, "shortest hit (s)");
    p.AddFlag("--max-duration-s", &shape.max_duration_s, "longest hit (s)");
    p.AddFlag("--keyword-thresholds", &split_thresholds,
              "per-keyword thresholds separated by ':' (one per keyword), instead of --thresholds");
    std::string array_recall;
    double call_az = 60, babble_az = -60;
    p.AddFlag(
        "--array-recall", &array_recall,
        "also: recall of the multichannel path (MVDR beam per track) on this array file, e.g. "
        "config/arrays/respeaker4.yaml, for each --max-utterances-s x --call-joins-s");
    p.AddFlag("--call-azimuth-deg", &call_az, "with --array-recall: caller's azimuth");
    p.AddFlag("--babble-azimuth-deg", &babble_az, "with --array-recall: other talker's azimuth");
    speech::VadOptions vad;
    p.AddFlag("--vad-threshold-db", &vad.threshold_db,
              "voice activity: speech this far above the noise floor (dB)");
    p.AddFlag("--vad-fluctuation-factor", &vad.fluctuation_factor,
              "voice activity: threshold at least this times the noise's mean level change per "
              "frame (0: off)");
    std::string fit_features, verifier_probs;
    p.AddFlag(
        "--fit-verifier", &fit_features,
        "comma-separated hit features: fit the keyword verifier on the tuning half and apply it "
        "(keyword_verifier.h; e.g. tilt_db)");
    p.AddFlag("--confusers", &o.num_confusers,
              "also: this many short espeak-ng phrases without 'help' in the calls' noise "
              "(synthetic false alarms)");
    p.AddFlag("--tts", &o.tts,
              "synthesiser of the calls, confusers and synthetic negatives: espeak or flite");
    p.AddFlag("--fit-l2", &o.fit_l2, "with --fit-verifier: L2 penalty on the standardised weights");
    p.AddFlag("--verifier-probabilities", &verifier_probs,
              "comma-separated verifier min_probability values, swept as a post-filter");
    std::string config_path;
    p.AddFlag("--config", &config_path,
              "speech YAML: evaluate its speech.keywords.verifier (even when off there), e.g. "
              "config/speech.yaml");
    p.AddFlag("--features-csv", &o.features_csv,
              "write one CSV row per hit with its features, its half (tune / held) and source");
    p.AddFlag(
        "--dump", &o.dump,
        "on stderr: hits (every utterance and hit) or llr (also the slow acoustic verification)");
    p.AddFlag("--segment-dir", &o.segment_dir,
              "write each utterance with a hit (at most 2 s) there as raw s16le, named by label "
              "and time");
    bool no_post_filter = false;
    p.AddSwitch("--no-post-filter", &no_post_filter,
                "with --array-recall: beam without the spectral-gain post-filter");
    if (!p.Parse(argc, argv)) return 0;
    if (o.tts != "espeak" && o.tts != "flite") throw common::ArgError("--tts: espeak or flite");
    if (!o.dump.empty() && o.dump != "hits" && o.dump != "llr")
      throw common::ArgError("--dump: hits or llr");
    if (!o.dump.empty()) common::SetLogLevel(common::LogLevel::DEBUG);  // the beam's segments too
    if (o.tts == "espeak" && !speech::EspeakAvailable())
      throw common::ArgError("espeak-ng is needed to render the calls");
    if (o.tts == "flite" && !speech::FliteAvailable())
      throw common::ArgError("flite is needed for --tts flite (apt-get install flite)");
    auto split = [](const std::string& s) {
      std::vector<std::string> out;
      size_t a = 0;
      while (a <= s.size()) {
        const size_t b = s.find(',', a);
        out.push_back(s.substr(a, b == std::string::npos ? std::string::npos : b - a));
        if (b == std::string::npos) break;
        a = b + 1;
      }
      return out;
    };
    if (!fit_features.empty()) o.fit_verifier_features = split(fit_features);
    speech::VerifierOptions config_verifier;
    if (!config_path.empty()) {
      const auto so = common::LoadOptions<speech::SpeechOptions>(
          common::ResolveConfigPath(config_path), {}, "speech");
      config_verifier = so.keywords.verifier;
      config_verifier.enabled = true;  // evaluated even when the node has it off
    }
    std::vector<double> vprobs;
    if (!verifier_probs.empty())
      for (const auto& c : split(verifier_probs)) vprobs.push_back(std::stod(c));
    const auto data = speech::MakeKwsEvalData(o);
    std::printf("data: %zu calls, %.1f min of other speech and noise\n", data.positives.size(),
                data.negatives.size() / 16000.0 / 60);
    std::printf(
        "| threshold | call join s | max call s | min confidence | recall (help) | hits/calls | "
        "help false alarms | per 10 min | other-keyword alarms "
        "| tune recall | tune FA/10 min | held-out recall | held-out FA/10 min | CPU s | synthetic "
        "confusers with a 'help' |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::vector<std::string> sweep = split(thresholds);
    if (!split_thresholds.empty()) sweep = {split_thresholds};
    for (const auto& t : sweep) {
      speech::KeywordOptions k = shape;
      k.verifier = config_verifier;
      k.keywords = split(keyword_list);
      k.thresholds.clear();
      size_t a = 0;
      while (a <= t.size()) {
        const size_t b = t.find(':', a);
        k.thresholds.push_back(
            std::stod(t.substr(a, b == std::string::npos ? std::string::npos : b - a)));
        if (b == std::string::npos) break;
        a = b + 1;
      }
      k.verify_acoustic = verify == "acoustic";
      k.min_confidence = min_conf;
      common::Validator check;
      common::CheckOptions(k, &check);
      if (!check.errors().empty())
        throw common::ArgError("invalid keyword settings: " + check.errors().front());
      k.verify_with_lm = verify == "lm";
      k.verify_with_grammar = verify == "grammar";
      k.cmn = cmn;
      k.full_utterance = full_utt;
      std::vector<double> cuts;
      for (const auto& c : split(confidences)) cuts.push_back(std::stod(c));
      std::vector<double> max_utts;
      for (const auto& c : split(max_utterances)) max_utts.push_back(std::stod(c));
      std::vector<double> gaps;
      for (const auto& c : split(call_joins)) gaps.push_back(std::stod(c));
      if (!array_recall.empty()) {
        for (double join : gaps)
          for (double mu : max_utts) {
            speech::KeywordOptions ka = k;
            ka.max_utterance_s = mu;
            ka.call_join_s = join;
            const auto r = speech::KwsArrayRecall(data, array_recall, ka, call_az, babble_az, vad,
                                                  !no_post_filter);
            std::printf(
                "array %s, caller %.0f deg, other talker %.0f deg: threshold %s, call join %.2f s, "
                "max call "
                "%.1f s: recall %.3f (%d/%d); 'help' outside the calls (after each cold start) %d "
                "in %.1f min\n",
                array_recall.c_str(), call_az, babble_az, t.c_str(), join, mu,
                r.calls ? static_cast<double>(r.hits) / r.calls : 0.0, r.hits, r.calls,
                r.false_hits, r.false_hit_seconds / 60);
            std::fflush(stdout);
          }
        continue;
      }
      const auto rs = speech::EvaluateKwsSweep(data, k, vad, o, cuts, max_utts, gaps, vprobs);
      if (!rs.empty() && rs.front().verifier.enabled) {
        const auto& v = rs.front().verifier;
        std::printf("verifier%s (config/speech.yaml speech.keywords.verifier):\n",
                    o.fit_verifier_features.empty() ? "" : " fitted on the tuning half");
        auto list = [](const std::vector<double>& xs) {
          std::string s;
          for (double x : xs) s += (s.empty() ? "" : ", ") + std::to_string(x);
          return "[" + s + "]";
        };
        std::string names;
        for (const auto& n : v.features) names += (names.empty() ? "" : ", ") + n;
        std::printf("  features: [%s]\n  means: %s\n  scales: %s\n  weights: %s\n  bias: %f\n",
                    names.c_str(), list(v.means).c_str(), list(v.scales).c_str(),
                    list(v.weights).c_str(), v.bias);
        std::printf(
            "| call join s | max call s | verifier p >= | tune recall | tune FA/10 min "
            "(real+synthetic) | "
            "held-out recall | held-out FA/10 min (real+synthetic) | verifier passes: calls / real "
            "/ synthetic "
            "negative hits | synthetic confusers with a 'help' "
            "|\n|---|---|---|---|---|---|---|---|---|\n");
        for (const auto& r : rs)
          std::printf(
              "| %.2f | %.1f | %.3f | %.3f | %.1f (%d+%d) | %.3f (%d/%d) | %.1f (%d+%d) | %.2f / "
              "%.2f / %.2f | %d/%d |\n",
              r.call_join_s, r.max_utterance_s, r.verifier_min_probability, r.tune_recall,
              r.tune_fa_per_10_min, r.tune_fa_real, r.tune_fa_synthetic, r.held_recall, r.held_hits,
              r.held_calls, r.held_fa_per_10_min, r.held_fa_real, r.held_fa_synthetic,
              r.verifier_pass_calls, r.verifier_pass_real, r.verifier_pass_synthetic,
              r.confuser_false_alarms, r.confuser_scenes);
        std::fflush(stdout);
        continue;
      }
      for (const auto& r : rs)
        std::printf(
            "| %s | %.2f | %.1f | %.2f | %.3f | %d/%d | %d | %.2f | %d | %.3f | %.2f | %.3f "
            "(%d/%d) | %.2f (%d) | %.1f | %d/%d |\n",
            t.c_str(), r.call_join_s, r.max_utterance_s, r.min_confidence, r.recall, r.hits,
            r.calls, r.target_false_alarms, r.false_alarms_per_10_min, r.other_false_alarms,
            r.tune_recall, r.tune_fa_per_10_min, r.held_recall, r.held_hits, r.held_calls,
            r.held_fa_per_10_min, r.held_false_alarms, r.decode_seconds, r.confuser_false_alarms,
            r.confuser_scenes);
      std::fflush(stdout);
    }
    return 0;
  });
}
