// The viewer's camera, shared by every mode: `prt render`'s pinhole camera (EYE, TARGET, UP, FOVY; docs/bundle.md)
// as a three.js PerspectiveCamera, and orbit about the target.
import * as THREE from 'three';

// `count` comma-separated finite numbers from `text`; throws Error naming the parameter otherwise.
export function parseNumbers(text, count, name) {
  const values = text.split(',').map(Number);
  if (values.length !== count || values.some((v) => !Number.isFinite(v))) throw new Error(`${name}: need ${count} numbers`);
  return values;
}

// {orbit: {eye, target, up, fovy}, camera, place(), turn(yaw, pitch, zoom), array()} for the 10 numbers `view`.
// place() sets the camera from the orbit (near and far at 1e-3 and 1e3 times the distance); turn() orbits about
// the target: `yaw` and `pitch` in degrees about the up axis and the camera's right axis, `zoom` a factor on the
// distance, the pitch stopping 1 degree short of the poles.
export function orbitCamera(view, width, height) {
  const camera = new THREE.PerspectiveCamera(view[9], width / height, 1e-3, 1e3);
  const orbit = { eye: new THREE.Vector3(view[0], view[1], view[2]), target: new THREE.Vector3(view[3], view[4], view[5]),
                  up: new THREE.Vector3(view[6], view[7], view[8]), fovy: view[9] };
  return {
    orbit,
    camera,
    place() {
      const distance = orbit.eye.distanceTo(orbit.target);
      camera.near = distance * 1e-3;
      camera.far = distance * 1e3;
      camera.fov = orbit.fovy;
      camera.updateProjectionMatrix();
      camera.position.copy(orbit.eye);
      camera.up.copy(orbit.up);
      camera.lookAt(orbit.target);
    },
    set(values) {
      orbit.eye.fromArray(values, 0);
      orbit.target.fromArray(values, 3);
      orbit.up.fromArray(values, 6);
      orbit.fovy = values[9];
    },
    turn(yaw, pitch, zoom = 1) {
      const up = orbit.up.clone().normalize();
      const offset = orbit.eye.clone().sub(orbit.target);
      offset.applyAxisAngle(up, -yaw * Math.PI / 180);
      const right = offset.clone().cross(up).normalize();
      const angle = offset.angleTo(up) * 180 / Math.PI;
      const limited = Math.max(1 - angle, Math.min(179 - angle, pitch));
      offset.applyAxisAngle(right, -limited * Math.PI / 180);
      offset.multiplyScalar(zoom);
      orbit.eye.copy(orbit.target).add(offset);
    },
    array: () => [...orbit.eye.toArray(), ...orbit.target.toArray(), ...orbit.up.toArray(), orbit.fovy],
  };
}
