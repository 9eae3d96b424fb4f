#pragma once
// audio_common_msgs/AudioData, AudioDataStamped and AudioInfo for rosbag (Debian ships no C++
// headers for audio_common_msgs): plain structs with the ROS message traits and serialisers,
// with the definitions and MD5 sums of audio_common (the MD5 sums are computed the way genmsg
// does, from the definitions, so rosbag tools and rospy accept the files).

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <std_msgs/Header.h>

#include <cstdint>
#include <string>
#include <vector>

namespace audio_common_msgs {

struct AudioData {
  std::vector<uint8_t> data;
};

struct AudioDataStamped {
  std_msgs::Header header;
  AudioData audio;
};

struct AudioInfo {
  uint8_t channels = 0;
  uint32_t sample_rate = 0;
  std::string sample_format;  // e.g. "S16LE"
  uint32_t bitrate = 0;
  std::string coding_format;  // "wave" (raw PCM) or "mp3"
};

}  // namespace audio_common_msgs

namespace ros {
namespace message_traits {

template <>
struct MD5Sum<audio_common_msgs::AudioData> {
  static const char* value() { return "f43a8e1b362b75baa741461b46adc7e0"; }
  static const char* value(const audio_common_msgs::AudioData&) { return value(); }
};
template <>
struct DataType<audio_common_msgs::AudioData> {
  static const char* value() { return "audio_common_msgs/AudioData"; }
  static const char* value(const audio_common_msgs::AudioData&) { return value(); }
};
template <>
struct Definition<audio_common_msgs::AudioData> {
  static const char* value() { return "uint8[] data\n"; }
  static const char* value(const audio_common_msgs::AudioData&) { return value(); }
};

template <>
struct MD5Sum<audio_common_msgs::AudioDataStamped> {
  static const char* value() { return "3cdd84a06846af0dca4d0434908f9d96"; }
  static const char* value(const audio_common_msgs::AudioDataStamped&) { return value(); }
};
template <>
struct DataType<audio_common_msgs::AudioDataStamped> {
  static const char* value() { return "audio_common_msgs/AudioDataStamped"; }
  static const char* value(const audio_common_msgs::AudioDataStamped&) { return value(); }
};
template <>
struct Definition<audio_common_msgs::AudioDataStamped> {
  static const char* value() {
    // The dependencies' definitions follow, as genmsg writes them.
    static const std::string text =
        std::string("std_msgs/Header header\naudio_common_msgs/AudioData audio\n\n") +
        "================================================================================\n"
        "MSG: std_msgs/Header\n" +
        Definition<std_msgs::Header>::value() +
        "\n================================================================================\n"
        "MSG: audio_common_msgs/AudioData\nuint8[] data\n";
    return text.c_str();
  }
  static const char* value(const audio_common_msgs::AudioDataStamped&) { return value(); }
};
template <>
struct HasHeader<audio_common_msgs::AudioDataStamped> : TrueType {};

template <>
struct MD5Sum<audio_common_msgs::AudioInfo> {
  static const char* value() { return "9413d9b7029680d3b1db6ed0ae535f88"; }
  static const char* value(const audio_common_msgs::AudioInfo&) { return value(); }
};
template <>
struct DataType<audio_common_msgs::AudioInfo> {
  static const char* value() { return "audio_common_msgs/AudioInfo"; }
  static const char* value(const audio_common_msgs::AudioInfo&) { return value(); }
};
template <>
struct Definition<audio_common_msgs::AudioInfo> {
  static const char* value() {
    return "uint8 channels\nuint32 sample_rate\nstring sample_format\nuint32 bitrate\n"
           "string coding_format\n";
  }
  static const char* value(const audio_common_msgs::AudioInfo&) { return value(); }
};

}  // namespace message_traits

namespace serialization {

template <>
struct Serializer<audio_common_msgs::AudioData> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream& stream, T m) {
    stream.next(m.data);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};

template <>
struct Serializer<audio_common_msgs::AudioDataStamped> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream& stream, T m) {
    stream.next(m.header);
    stream.next(m.audio);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};

template <>
struct Serializer<audio_common_msgs::AudioInfo> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream& stream, T m) {
    stream.next(m.channels);
    stream.next(m.sample_rate);
    stream.next(m.sample_format);
    stream.next(m.bitrate);
    stream.next(m.coding_format);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};

}  // namespace serialization
}  // namespace ros
