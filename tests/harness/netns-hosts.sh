# Several "computers" on one machine, for the two-computer demo and tests: network namespaces
# joined by veth pairs to a bridge br0 in the current namespace (10.77.0.1), each with a
# multicast route, so LCM at ttl=1 crosses between them as on a robot's network.
# Source it from bash, in a namespace of your own (and a private mount namespace for
# /run/netns), then:
#   netns_bridge_up || { echo "cannot"; exit 77; }
#   netns_add_host NAMESPACE INDEX     # INDEX >= 2: address 10.77.0.INDEX, bridge port vpINDEX
#   netns_remove_hosts NAMESPACE...    # kills what runs inside and deletes them

netns_bridge_up() {
  mkdir -p /run/netns && mount -t tmpfs tmpfs /run/netns && ip link add br0 type bridge || return 1
  ip link set lo up
  ip link set br0 type bridge mcast_snooping 0   # flood multicast to every port (no querier here)
  ip addr add 10.77.0.1/24 dev br0
  ip link set br0 up
  ip route replace 224.0.0.0/4 dev br0
}

netns_add_host() {
  local ns="$1" i="$2"
  ip netns add "$ns"
  ip link add "vp$i" type veth peer name eth0 netns "$ns"
  ip link set "vp$i" master br0
  ip link set "vp$i" up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "10.77.0.$i/24" dev eth0
  ip -n "$ns" link set eth0 up
  ip -n "$ns" link set eth0 multicast on
  ip -n "$ns" route add 224.0.0.0/4 dev eth0
}

netns_remove_hosts() {
  local ns p
  for ns in "$@"; do
    for p in $(ip netns pids "$ns" 2>/dev/null); do kill -KILL "$p" 2>/dev/null; done
    ip netns del "$ns" 2>/dev/null
  done
  return 0
}
