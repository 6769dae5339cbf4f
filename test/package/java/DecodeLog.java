// Reads an LCM log with the motormix types of the jar under test, as lcm-spy
// would: every event on the given channels must decode with its class (the
// fingerprint and the layout agree with the C++ encoder that wrote it), and
// the decoded outputs must say what the mixer promises (sizes that agree,
// armed PWM within the configured range).
//   java -cp JAR:LCM_JAR:. DecodeLog LOG PWM_MIN PWM_MAX CHANNEL=TYPE...
import java.io.EOFException;
import java.util.LinkedHashMap;
import java.util.Map;
import lcm.logging.Log;
import motormix.motor_pwm_t;

public class DecodeLog {
  public static void main(String[] args) throws Exception {
    if (args.length < 4) {
      System.err.println("usage: DecodeLog LOG PWM_MIN PWM_MAX CHANNEL=TYPE...");
      System.exit(2);
    }
    final double pwmMin = Double.parseDouble(args[1]);
    final double pwmMax = Double.parseDouble(args[2]);
    final Map<String, Class<?>> types = new LinkedHashMap<>();
    final Map<String, Integer> decoded = new LinkedHashMap<>();
    for (int k = 3; k < args.length; ++k) {
      final String[] pair = args[k].split("=", 2);
      types.put(pair[0], Class.forName("motormix." + pair[1]));
      decoded.put(pair[0], 0);
    }
    int armed = 0;
    final Log log = new Log(args[0], "r");
    try {
      while (true) {
        final Log.Event ev = log.readNext();
        final Class<?> type = types.get(ev.channel);
        if (type == null) continue;
        // Throws when the fingerprint or the layout disagrees.
        final Object message = type.getConstructor(byte[].class).newInstance((Object) ev.data);
        decoded.put(ev.channel, decoded.get(ev.channel) + 1);
        if (message instanceof motor_pwm_t) {
          final motor_pwm_t m = (motor_pwm_t) message;
          if (m.pwm.length != m.num_motors || m.command.length != m.num_motors
              || m.direction.length != m.num_motors) {
            fail("motor_pwm_t at " + ev.utime + ": arrays disagree with num_motors " + m.num_motors);
          }
          if (!m.armed) continue;
          ++armed;
          for (float pwm : m.pwm) {
            if (!(pwm >= pwmMin && pwm <= pwmMax)) {
              fail("armed pwm " + pwm + " outside " + pwmMin + ".." + pwmMax + " at " + ev.utime);
            }
          }
        }
      }
    } catch (EOFException end) {
      // the whole log was read
    } finally {
      log.close();
    }
    for (Map.Entry<String, Integer> e : decoded.entrySet()) {
      System.out.println(e.getKey() + ": " + e.getValue() + " messages decoded as "
          + types.get(e.getKey()).getName());
      if (e.getValue() == 0) fail("no message on channel " + e.getKey());
    }
    if (types.containsValue(motor_pwm_t.class) && armed == 0) fail("no armed output in the log");
    System.out.println("armed outputs checked: " + armed);
  }

  private static void fail(String why) {
    System.err.println("DecodeLog: FAIL: " + why);
    System.exit(1);
  }
}
