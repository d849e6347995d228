// Decodes every event of an LCM log with the classes lcm-spy would use (lcm.spy.LCMTypeDatabase
// over the class path, i.e. fact_lcmtypes.jar) and re-encodes it: the bytes must be identical.
// Run with the JDK's source launcher (test_lcm_spy.sh):
//   java -cp /usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:fact_lcmtypes.jar LcmDecodeCheck.java LOG
// Prints "CHANNEL TYPE BYTES" per decoded event; "UNDECODED ..." and exit 1 on any failure.
import java.io.ByteArrayOutputStream;
import java.io.DataInputStream;
import java.io.DataOutputStream;
import java.io.ByteArrayInputStream;
import java.io.EOFException;
import java.util.Arrays;

public class LcmDecodeCheck {
  public static void main(String[] args) throws Exception {
    if (args.length != 1) {
      System.err.println("usage: LcmDecodeCheck LOG");
      System.exit(2);
    }
    lcm.spy.LCMTypeDatabase types = new lcm.spy.LCMTypeDatabase();
    lcm.logging.Log log = new lcm.logging.Log(args[0], "r");
    int events = 0, failures = 0;
    while (true) {
      lcm.logging.Log.Event e;
      try {
        e = log.readNext();
      } catch (EOFException eof) {
        break;
      }
      if (e == null) break;
      ++events;
      long fingerprint = new DataInputStream(new ByteArrayInputStream(e.data)).readLong();
      Class<?> cls = types.getClassByFingerprint(fingerprint);
      if (cls == null) {
        System.out.println("UNDECODED " + e.channel + ": no class for fingerprint " + Long.toHexString(fingerprint));
        ++failures;
        continue;
      }
      try {
        Object msg = cls.getConstructor(byte[].class).newInstance((Object) e.data);
        ByteArrayOutputStream bytes = new ByteArrayOutputStream();
        ((lcm.lcm.LCMEncodable) msg).encode(new DataOutputStream(bytes));
        if (!Arrays.equals(bytes.toByteArray(), e.data)) {
          System.out.println("UNDECODED " + e.channel + ": " + cls.getName() + " re-encodes to different bytes");
          ++failures;
          continue;
        }
        System.out.println(e.channel + " " + cls.getName() + " " + e.data.length);
      } catch (Exception ex) {
        System.out.println("UNDECODED " + e.channel + ": " + cls.getName() + ": " + ex);
        ++failures;
      }
    }
    log.close();
    System.out.println(events + " events, " + failures + " failures");
    System.exit(failures == 0 && events > 0 ? 0 : 1);
  }
}
