"""The SPENCER framework's own message types, registered from their .msg text so that rosbags can write them
without ROS.

The definitions are those of spencer-project/spencer_people_tracking (``messages/spencer_tracking_msgs/msg/*.msg``,
``messages/spencer_social_relation_msgs/msg/*.msg``), fields and constants as there, comments left out (they are
not part of a type's md5 or RIHS01 hash). ROS 1 names are resolved as rosbags resolves them: ``Header`` is
std_msgs/Header, ``duration`` builtin_interfaces/Duration (ROS 1's duration on the wire). With these texts
rosbags gives the md5 sums genmsg gives for the spencer_tracking_msgs types; for SocialRelation(s) it does not
(genmsg keeps the quotes of ``TYPE_SPATIAL = "spatial"`` in the hashed text, rosbags strips them), which matters
only to a ROS 1 subscriber, and no export writes SocialRelations yet (the dataset has no relations).
"""

from __future__ import annotations

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

MSGS = {
    "spencer_tracking_msgs/msg/DetectedPerson": """
uint64 detection_id
float64 confidence
geometry_msgs/PoseWithCovariance pose
string modality
string MODALITY_GENERIC_LASER_2D = laser2d
string MODALITY_GENERIC_LASER_3D = laser3d
string MODALITY_GENERIC_MONOCULAR_VISION = mono
string MODALITY_GENERIC_STEREO_VISION = stereo
string MODALITY_GENERIC_RGBD = rgbd
""",
    "spencer_tracking_msgs/msg/DetectedPersons": """
Header header
DetectedPerson[] detections
""",
    "spencer_tracking_msgs/msg/TrackedPerson": """
uint64 track_id
bool is_occluded
bool is_matched
uint64 detection_id
duration age
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
""",
    "spencer_tracking_msgs/msg/TrackedPersons": """
Header header
TrackedPerson[] tracks
""",
    "spencer_tracking_msgs/msg/TrackedGroup": """
uint64 group_id
duration age
geometry_msgs/PoseWithCovariance centerOfGravity
uint64[] track_ids
""",
    "spencer_tracking_msgs/msg/TrackedGroups": """
Header header
TrackedGroup[] groups
""",
    "spencer_social_relation_msgs/msg/SocialRelation": """
string type
float32 strength
uint32 track1_id
uint32 track2_id
string TYPE_SPATIAL = "spatial"
string TYPE_ROMANTIC = "romantic"
string TYPE_PARENT_CHILD = "parent_child"
string TYPE_FRIENDSHIP = "friendship"
""",
    "spencer_social_relation_msgs/msg/SocialRelations": """
std_msgs/Header header
SocialRelation[] elements
""",
}
# ROS 1's tf2_msgs/TFMessage (ros/geometry2 tf2_msgs/msg/TFMessage.msg), which rosbags' ROS1_NOETIC store lacks
TF_MESSAGE = {"tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms\n"}


def typestore(ros: int):
    """rosbags' store of ROS 1 Noetic's or ROS 2 Humble's standard types, with SPENCER's (and, for ROS 1,
    TFMessage) added."""
    store = get_typestore(Stores.ROS1_NOETIC if ros == 1 else Stores.ROS2_HUMBLE)
    texts = {**MSGS, **({} if "tf2_msgs/msg/TFMessage" in store.types else TF_MESSAGE)}
    types = {}
    for name, text in texts.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store
