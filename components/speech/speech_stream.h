#pragma once
// What sarmap-speech does with its inputs, without the transport: DOA tracks steer the
// processor's beams (a DOA's time is put on the audio's sample clock through the latest audio
// block's stamp), and each audio block's finished utterances come out as SPEECH events and, for
// a keyword with a direction, PEOPLE_AUDIO. The node (speech_node.cc) checks and sequences the
// blocks and publishes; the in-process mission (components/mission) feeds SpeechStream directly.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sarmap/doa_t.hpp"
#include "sarmap/people_detections_t.hpp"
#include "sarmap/speech_event_t.hpp"
#include "speech/speech_messages.h"
#include "speech/speech_processor.h"

namespace sarmap {
namespace speech {

class SpeechStream {
 public:
  // Throws std::invalid_argument / std::runtime_error on an unusable array or options.
  SpeechStream(const SpeechNodeOptions& options, const common::MicArrayOptions& array);

  const sound::ArrayGeometry& geometry() const { return geometry_; }
  sound::DoaKind kind() const { return kind_; }
  SpeechProcessor& processor() { return *processor_; }
  const SpeechProcessor& processor() const { return *processor_; }

  // A DOA message of `device` (the processor listens to one device: others are ignored). Its
  // tracked directions steer the beams; `warnings` gets a line per direction refused (another
  // kind than this node's search, or stamped too far ahead of the audio).
  void OnDoa(const sarmap::doa_t& msg, const std::string& device,
             std::vector<std::string>* warnings);
  // One interleaved int16 block stamped `utime` (its first sample). Appends a SPEECH event per
  // result, and a PEOPLE_AUDIO message per keyword with a direction (`people`; sensor_id
  // `device`).
  void OnAudio(const int16_t* data, int frames, int block_channels, int64_t utime,
               const std::string& device, std::vector<sarmap::speech_event_t>* events,
               std::vector<sarmap::people_detections_t>* people);
  // Ends the utterances still open (at the end of a stream), as OnAudio appends results.
  void Flush(const std::string& device, std::vector<sarmap::speech_event_t>* events,
             std::vector<sarmap::people_detections_t>* people);
  // The results of the last OnAudio or Flush (for logs).
  const std::vector<SpeechResult>& last_results() const { return results_; }

 private:
  int64_t ToUtime(int64_t sample) const;
  // SPEECH for every result in results_, PEOPLE_AUDIO for each keyword with a direction.
  void Emit(const std::string& device, std::vector<sarmap::speech_event_t>* events,
            std::vector<sarmap::people_detections_t>* people) const;

  SpeechNodeOptions options_;
  sound::ArrayGeometry geometry_;
  sound::DoaKind kind_;
  std::unique_ptr<SpeechProcessor> processor_;
  // Anchor between stream samples and utime (from the latest audio block).
  int64_t anchor_sample_ = -1, anchor_utime_ = 0;
  std::vector<SpeechResult> results_;
};

}  // namespace speech
}  // namespace sarmap
