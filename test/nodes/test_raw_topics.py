"""The raw-topic follower the recorder and the Foxglove bridge share."""
from __future__ import annotations


def test_follows_new_topics_once_and_validates_its_period(rclpy_context):
    import rclpy
    from rclpy.parameter import Parameter
    from std_msgs.msg import String

    from mt_accuracy_ros.nodes._raw_topics import RawTopicFollower

    node = rclpy.create_node("follower_under_test")
    talker = rclpy.create_node("talker")
    publisher = talker.create_publisher(String, "/follow_me", 10)
    seen, received = [], []

    def on_new(name, type_name, offered):
        seen.append((name, type_name, offered[0]["reliability"]))
        return received.append

    follower = RawTopicFollower(node, {"/follow_me"}, 0.1, on_new, "following")
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    executor.add_node(talker)
    try:
        for _ in range(400):  # discovery: up to 20 s on a loaded host
            if seen:
                break
            executor.spin_once(timeout_sec=0.05)
        for _ in range(200):
            if publisher.get_subscription_count():
                break
            executor.spin_once(timeout_sec=0.05)
        publisher.publish(String(data="hello"))
        for _ in range(200):
            if received:
                break
            executor.spin_once(timeout_sec=0.05)
        follower.discover()
        assert seen == [("/follow_me", "std_msgs/msg/String", "reliable")]  # once only
        assert isinstance(received[0], bytes)  # raw CDR, never decoded
        assert not follower.validate([Parameter("discovery_period_s", value=0.001)]).successful
        assert follower.validate([Parameter("discovery_period_s", value=2.0)]).successful
    finally:
        executor.shutdown()
        talker.destroy_node()
        node.destroy_node()
