"""Small rospy programs run with Debian's python3: the real ROS 1 peers the tests talk to."""

HELLO_PUBLISHER = """
import rospy
from std_msgs.msg import String
rospy.init_node('hello_world_pub_node')
pub = rospy.Publisher('hello_world', String, queue_size=10)
rate = rospy.Rate(5)
i = 0
while not rospy.is_shutdown():
    pub.publish(String(data="Hello_World_%d" % i))
    i += 1
    rate.sleep()
"""

HELLO_SUBSCRIBER = """
import sys
import rospy
from std_msgs.msg import String
rospy.init_node('hello_world_sub_node')
def process_hello_world_message(msg):
    print("Message received: " + msg.data, flush=True)
rospy.Subscriber('hello_world', String, process_hello_world_message)
rospy.spin()
"""

# Prints every message it gets as "TYPE|repr" lines, so tests can assert exact values.
TYPED_SUBSCRIBER = """
import sys
import rospy
import roslib.message
topic, type_name = sys.argv[1], sys.argv[2]
cls = roslib.message.get_message_class(type_name)
rospy.init_node('probe_sub', anonymous=True)
def on(msg):
    print(repr(msg).replace("\\n", " "), flush=True)
rospy.Subscriber(topic, cls, on)
print("READY", flush=True)
rospy.spin()
"""

LATCHED_SCAN = """
import rospy
from sensor_msgs.msg import LaserScan
from geometry_msgs.msg import PoseStamped
rospy.init_node('scanner')
scan_pub = rospy.Publisher('scan', LaserScan, queue_size=1, latch=True)
pose_pub = rospy.Publisher('pose', PoseStamped, queue_size=1, latch=True)
scan = LaserScan()
scan.header.frame_id = 'laser'
scan.header.stamp = rospy.Time(12, 5000)
scan.angle_min = -1.5
scan.ranges = [1.0, 1.2, 0.9]
scan_pub.publish(scan)
pose = PoseStamped()
pose.header.stamp = rospy.Time(3, 7)
pose.header.frame_id = 'map'
pose.pose.position.x = 0.1
pose.pose.orientation.w = 1.0
pose_pub.publish(pose)
rospy.spin()
"""

FAST_PUBLISHER = """
import sys
import rospy
from std_msgs.msg import Int32
rospy.init_node('fast_pub')
pub = rospy.Publisher('fast', Int32, queue_size=1000)
rate = rospy.Rate(float(sys.argv[1]))
i = 0
while not rospy.is_shutdown():
    pub.publish(Int32(data=i))
    i += 1
    rate.sleep()
"""

# A type no built-in store knows, generated at run time by genpy from its text (as rosbag does).
CUSTOM_TYPE_PUBLISHER = """
import rospy
import genpy.dynamic
text = '''# a sensor reading the book's W9 publishes
float32 temperature
float32 threshold
string status
int16[] history
geometry_msgs/Point where
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
'''
classes = genpy.dynamic.generate_dynamic('book_msgs/TemperatureStatus', text)
Msg = classes['book_msgs/TemperatureStatus']
rospy.init_node('temperature_publisher')
pub = rospy.Publisher('temperature', Msg, queue_size=1, latch=True)
msg = Msg(temperature=31.0, threshold=30.0, status='ALERT', history=[29, 30, 31])
msg.where.x = 1.5
pub.publish(msg)
print(Msg._md5sum, flush=True)
rospy.spin()
"""
